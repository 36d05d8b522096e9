#include "sim/rig_draw.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "sim/random.hpp"
#include "sim/rig.hpp"

namespace leakmon::sim {

namespace {

double log_uniform(Random& random, double lo, double hi) {
  return std::exp(random.uniform(std::log(lo), std::log(hi)));
}

// The stream the drawer takes its numbers from, apart from the simulation's own streams.
constexpr std::uint64_t kRigStream = 0x7269672d64726177ULL;  // "rig-draw"
constexpr int kMaxAttempts = 500;

RigDescription draw_description(Random& random) {
  RigDescription rig;
  auto set = [&rig](std::string_view key, double value) { rig = with_value(rig, key, value); };
  const double bore = log_uniform(random, 0.025, 0.100);
  set("bore", bore);
  set("rod", bore * random.uniform(0.4, 0.7));
  set("stroke", log_uniform(random, 0.1, 1.0));
  set("dead_volume", log_uniform(random, 5e-6, 5e-5));
  set("line_volume", log_uniform(random, 2e-5, 5e-4));
  const double ps = random.uniform(7e6, 28e6);
  set("supply_pressure", ps);
  set("tank_pressure", random.uniform(0.0, 1e6));
  set("bulk_modulus", random.uniform(0.5e9, 1.5e9));
  set("moving_mass", log_uniform(random, 2.0, 500.0));
  set("viscous_friction", log_uniform(random, 50.0, 5000.0));
  // One rig in ten carries no spring (a free mass or a rig without a specimen): at rest its
  // chambers then balance and a leak has no pressure difference to flow on.
  set("load_stiffness", random.uniform() < 0.1 ? 0.0 : random.uniform(10e3, 500e3));
  // A valve is sized for its cylinder: the no-load speed Kv sqrt(ps / 2) / A (1.6 m/s on the
  // paper's rig) of a servo rig lies within 0.4-4 m/s.
  const double area = rig.params.A();
  const double speed = log_uniform(random, 0.4, 4.0);
  set("valve_coefficient", std::clamp(speed * area / std::sqrt(ps / 2.0), 5e-8, 3e-6));
  set("valve_time_constant", log_uniform(random, 1e-3, 20e-3));
  set("command_full_scale", 10.0);
  set("null_leakage", log_uniform(random, 1e-13, 2e-12));
  const std::array grades = {32, 46, 68};
  rig.oil = *Oil::iso_vg(grades[static_cast<std::size_t>(random.uniform() * 3.0) % 3]);
  rig.stated.emplace_back("oil_grade");
  return rig;
}

double correlation(const std::vector<double>& a, const std::vector<double>& b, std::size_t from) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  const auto n = static_cast<double>(a.size() - from);
  for (std::size_t i = from; i < a.size(); ++i) {
    sa += a[i];
    sb += b[i];
    saa += a[i] * a[i];
    sbb += b[i] * b[i];
    sab += a[i] * b[i];
  }
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n;
  return va > 0 && vb > 0 ? (sab - sa * sb / n) / std::sqrt(va * vb) : 0.0;
}

// RMS of x about its centred moving average over 2 half + 1 samples, from sample `from` on.
double ringing_rms(const std::vector<double>& x, std::size_t from, std::size_t half) {
  std::vector<double> prefix(x.size() + 1, 0.0);
  for (std::size_t i = 0; i < x.size(); ++i) prefix[i + 1] = prefix[i] + x[i];
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = std::max(from, half); i + half < x.size(); ++i) {
    const double mean =
        (prefix[i + half + 1] - prefix[i - half]) / static_cast<double>(2 * half + 1);
    sum += (x[i] - mean) * (x[i] - mean);
    ++count;
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

}  // namespace

double hydraulic_mode_hz(const Parameters& p) {
  const double A = p.A();
  const double V = p.V0();
  const double hydraulic = p.beta * A * A * (2.0 / V) / p.m;
  return std::sqrt(hydraulic + p.K_s / p.m) / (2.0 * std::numbers::pi);
}

double max_step_amplitude(const Parameters& p) {
  double amplitude = std::min(0.05, 0.35 * p.L);
  if (p.K_s > 0.0) amplitude = std::min(amplitude, 0.45 * p.A() * (p.ps - p.pt) / p.K_s);
  return amplitude;
}

Scenario other_rig_scenario(const OtherRig& rig, ControllerKind controller, double seconds,
                            std::uint64_t seed) {
  Scenario s;
  s.name = "other-rig";
  s.origin = "other rig";
  s.controller = controller;
  s.duration_s = seconds;
  s.seed = seed;
  s.rig = rig.rig;
  s.params = rig.rig.params;
  s.conditions.oil = rig.rig.oil;
  s.reference = rig.reference;
  s.sensors = rig.sensors;
  return s;
}

Viability check_viability(const Scenario& scenario, double seconds, const ViabilityLimits& limits) {
  Scenario healthy = scenario;
  healthy.effects = Effects{};
  healthy.faults.clear();
  healthy.duration_s = seconds;
  Rig rig(healthy);
  const Parameters& p = healthy.params;
  const auto samples = static_cast<std::size_t>(std::llround(seconds / rig.sample_period()));
  std::vector<double> x(samples), xref(samples);
  std::size_t saturated = 0, pinned = 0;
  for (std::size_t i = 0; i < samples; ++i) {
    const RigSample s = rig.step();
    if (!std::isfinite(s.x_true) || !std::isfinite(s.p1_true) || !std::isfinite(s.p2_true)) {
      return {false, false, fmt::format("the states left the finite numbers at t = {:.3f} s", s.t)};
    }
    if (std::abs(s.x_true) > 0.45 * p.L) {
      return {false, false, fmt::format("the piston reached its end stop at t = {:.3f} s", s.t)};
    }
    if (std::abs(s.u) >= 0.999 * p.u_max) ++saturated;
    const double low = 0.01 * p.ps, high = 0.99 * p.ps;
    if (s.p1_true < low || s.p2_true < low || s.p1_true > high || s.p2_true > high) ++pinned;
    x[i] = s.x_true;
    xref[i] = s.xref;
  }
  const std::size_t settled = std::min(samples / 2, static_cast<std::size_t>(500));
  const double r = correlation(x, xref, settled);
  if (r < limits.min_correlation) {
    return {false, false, fmt::format("the position follows the reference poorly (r {:.2f})", r)};
  }
  const double ringing = ringing_rms(x, settled, 12);
  const double amplitude = healthy.reference.amp_max;
  if (ringing > limits.max_ringing * amplitude) {
    return {false, false,
            fmt::format("the position rings ({:.2g} mm around its 50 ms mean, {:.0f} % of "
                        "the step amplitude)",
                        ringing * 1e3, 100.0 * ringing / amplitude)};
  }
  const auto n = static_cast<double>(samples);
  if (static_cast<double>(saturated) > limits.max_saturated * n) {
    return {false, true,
            fmt::format("the command saturated in {:.1f} % of the samples",
                        100.0 * static_cast<double>(saturated) / n)};
  }
  if (static_cast<double>(pinned) > limits.max_pinned * n) {
    return {false, false,
            fmt::format("a chamber sat at tank or supply in {:.1f} % of the samples",
                        100.0 * static_cast<double>(pinned) / n)};
  }
  return {true, false, ""};
}

OtherRig draw_other_rig(std::uint64_t seed, ControllerKind controller) {
  Random random(stream_seed(seed, kRigStream));
  for (int attempt = 1; attempt <= kMaxAttempts; ++attempt) {
    OtherRig candidate;
    candidate.rig = draw_description(random);
    candidate.attempts = attempt;
    const Parameters& p = candidate.rig.params;
    const double amplitude = max_step_amplitude(p);
    if (amplitude < 5e-3) continue;  // a rig that cannot move 5 mm is not one to test on
    candidate.reference.amp_max = amplitude;
    candidate.reference.amp_min = amplitude / 2.0;
    candidate.sensors = sensors_for(p);
    // Two references of its own, so that a rig is not kept on one lucky sequence of steps.
    const auto trial = [&](std::uint64_t k) {
      return check_viability(
          other_rig_scenario(candidate, controller, 12.0, stream_seed(seed, 1000 * attempt + k)));
    };
    if (trial(1).ok && trial(2).ok) return candidate;
  }
  throw std::runtime_error(fmt::format("no rig the {} controller runs in {} draws (seed {})",
                                       to_string(controller), kMaxAttempts, seed));
}

RigDescription misstate(const RigDescription& stated, std::string_view key, double factor) {
  const auto value = rig_value(stated, key);
  if (!value) throw std::invalid_argument(fmt::format("unknown rig key '{}'", key));
  return with_value(stated, key, *value * factor);
}

}  // namespace leakmon::sim
