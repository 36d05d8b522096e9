#include "model/effect_library.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::model {
namespace {

double value_of(const std::vector<double>& values, std::size_t i) {
  return i < values.size() ? values[i] : 0.0;
}

}  // namespace

const std::vector<std::string>& effect_names() {
  static const std::vector<std::string> names = {
      "internal_leakage", "external_leakage", "coulomb_friction", "entrained_air",
      "valve_overlap",    "valve_bias",       "spool_lag",        "supply_ripple",
      "supply_droop",     "sensor_offset",    "sensor_lag"};
  return names;
}

std::vector<std::vector<double>> EffectCandidate::split(const std::vector<double>& values) const {
  if (parts.empty()) return {values};
  std::vector<std::vector<double>> out;
  std::size_t next = 0;
  for (const auto& part : parts) {
    std::vector<double> share;
    for (std::size_t i = 0; i < part.parameters.size(); ++i)
      share.push_back(value_of(values, next++));
    out.push_back(std::move(share));
  }
  return out;
}

EffectCandidate combine(const std::vector<EffectCandidate>& parts) {
  EffectCandidate joint;
  for (const auto& part : parts) {
    joint.effect += (joint.effect.empty() ? "" : "+") + part.effect;
    joint.onset_s = std::max(joint.onset_s, part.onset_s);
    joint.parameters.insert(joint.parameters.end(), part.parameters.begin(), part.parameters.end());
    joint.parts.push_back(part);
  }
  return joint;
}

void EffectCandidate::apply(EffectParameters& e, const std::vector<double>& values) const {
  if (!parts.empty()) {
    const auto shares = split(values);
    for (std::size_t i = 0; i < parts.size(); ++i) parts[i].apply(e, shares[i]);
    return;
  }
  std::vector<double> v(parameters.size());
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    v[i] = std::clamp(value_of(values, i), parameters[i].lower, parameters[i].upper);
  }
  const auto channel = variant == "p2" ? PressureChannel::p2 : PressureChannel::p1;
  if (effect == "internal_leakage") {
    e.C_L = v[0];
  } else if (effect == "external_leakage") {
    e.C_E = v[0];
    e.external_chamber = variant == "chamber 2" ? 2 : 1;
  } else if (effect == "coulomb_friction") {
    e.F_C = v[0];
  } else if (effect == "entrained_air") {
    e.alpha = v[0];
  } else if (effect == "valve_overlap") {
    e.d = v[0];
  } else if (effect == "valve_bias") {
    e.u0 = v[0];
  } else if (effect == "spool_lag") {
    e.spool_tau = v[0];
  } else if (effect == "supply_ripple") {
    e.ripple_dP = v[0];
    e.ripple_f = v[1];
    e.ripple_dQ = v[2];
  } else if (effect == "supply_droop") {
    e.R_s = v[0];
  } else if (effect == "sensor_offset") {
    e.offset = v[0];
    e.offset_channel = channel;
  } else if (effect == "sensor_lag") {
    e.tau_s = v[0];
    e.lag_channel = channel;
  } else if (effect == "oil_temperature") {
    e.visc_slope = v[0];
  }
}

RigScales RigScales::of(const sim::Parameters& rig) {
  const sim::Parameters paper;
  RigScales s;
  if (rig.Kv != paper.Kv) s.leak = rig.Kv / paper.Kv;
  const double span = rig.ps - rig.pt, paper_span = paper.ps - paper.pt;
  if (rig.A() != paper.A() || span != paper_span)
    s.force = rig.A() * span / (paper.A() * paper_span);
  if (rig.Kv != paper.Kv || span != paper_span) {
    s.droop =
        (span / (rig.Kv * std::sqrt(span))) / (paper_span / (paper.Kv * std::sqrt(paper_span)));
  }
  if (rig.u_max != paper.u_max) s.command = rig.u_max / paper.u_max;
  return s;
}

void EffectCandidate::apply(ModelParameters& p, const std::vector<double>& values) const {
  if (!parts.empty()) {
    const auto shares = split(values);
    for (std::size_t i = 0; i < parts.size(); ++i) parts[i].apply(p, shares[i]);
    return;
  }
  apply(p.effects, values);
  if (onset_s > 0.0) {
    p.onset_s = onset_s;
  } else {
    apply(p.before, values);
  }
}

double EffectCandidate::smallest() const {
  // A fifth of each range's low end (MODEL.md's effect library), on another rig times the
  // effect's size there. The evaluation's `beyond` class draws at the low end / 1.5, so every
  // instance it draws stays well above this.
  if (effect == "internal_leakage") return size * 5e-13 / 5.0;
  if (effect == "external_leakage") return size * 1e-13 / 5.0;
  if (effect == "coulomb_friction") return size * 50.0 / 5.0;
  if (effect == "entrained_air") return 0.02 / 5.0;
  if (effect == "valve_overlap") return 0.01 / 5.0;
  if (effect == "valve_bias") return size * 0.05 / 5.0;
  if (effect == "supply_droop") return size * 5e9 / 5.0;
  if (effect == "sensor_offset") return 5e4 / 5.0;
  if (effect == "sensor_lag") return std::max(0.002 / 5.0, 0.5 * sample_period);
  return 0.0;  // spool lag: slower than the nominal spool; ripple: its line test
}

bool EffectCandidate::plausible(const std::vector<double>& values) const {
  if (!parts.empty()) {
    const auto shares = split(values);
    for (std::size_t i = 0; i < parts.size(); ++i) {
      if (!parts[i].plausible(shares[i])) return false;
    }
    return true;
  }
  const double main = value_of(values, 0);
  const auto& p = parameters.front();
  // A main parameter pinned at a bound means the effect's shape does not fit the data.
  const double span = p.upper - p.lower;
  if (main <= p.lower + 1e-3 * span || main >= p.upper - 1e-3 * span) return false;
  if (effect == "spool_lag") return main > 1.5 * rig_spool_tau;  // slower than the rig's spool
  if (std::abs(main) < smallest()) return false;
  // Leaks, friction, air, dead band and droop have a sign; the solver may cross zero, but a
  // negative one is not an instance of the effect.
  const bool signed_effect = effect == "valve_bias" || effect == "supply_ripple" ||
                             effect == "sensor_offset" || effect == "sensor_lag";
  return signed_effect || main > 0.0;
}

std::vector<EffectCandidate> effect_library(double ripple_hz, bool has_temperature,
                                            double sample_period, const sim::Parameters& rig) {
  const RigScales k = RigScales::of(rig);
  // A parameter's scale, start and bounds times the effect's size on this rig.
  const auto sized = [](FreeParameter p, double size) {
    p.scale *= size;
    p.initial *= size;
    p.lower *= size;
    p.upper *= size;
    return p;
  };
  std::vector<EffectCandidate> out;
  out.push_back(
      {"internal_leakage", "", {sized({"C_L", 1e-12, 1e-12, -2e-12, 5e-11}, k.leak)}, {}});
  out.back().size = k.leak;
  for (const char* chamber : {"chamber 1", "chamber 2"}) {
    out.push_back(
        {"external_leakage", chamber, {sized({"C_E", 1e-12, 5e-13, -1e-12, 2e-11}, k.leak)}, {}});
    out.back().size = k.leak;
  }
  out.push_back(
      {"coulomb_friction", "", {sized({"F_C", 100.0, 100.0, -200.0, 4000.0}, k.force)}, {}});
  out.back().size = k.force;
  out.push_back({"entrained_air", "", {{"alpha", 0.05, 0.05, -0.02, 1.0}}, {}});
  out.push_back({"valve_overlap", "", {{"d", 0.01, 0.01, -0.01, 0.2}}, {}});
  out.push_back({"valve_bias", "", {sized({"u0", 0.1, 0.02, -3.0, 3.0}, k.command)}, {}});
  out.back().size = k.command;
  // The true spool's time constant, in multiples of the rig's own (the paper's rig's literal
  // values, 2.5 ms: scale 5 ms, start 6 ms, bounds 0.5-100 ms).
  const double tau = rig.tau;
  FreeParameter spool{"tau", 0.005, 0.006, 5e-4, 0.1};
  if (tau != sim::Parameters{}.tau) spool = {"tau", 2.0 * tau, 2.4 * tau, 0.2 * tau, 40.0 * tau};
  out.push_back({"spool_lag", "", {spool}, {}});
  if (ripple_hz > 0.0) {
    out.push_back({"supply_ripple",
                   "",
                   {{"dP", 1e5, 1e5, -5e6, 5e6},
                    // Held at the line test's frequency, good to ~1e-4 Hz: a solver step
                    // of 0.01 Hz already turns the phase by 3.8 rad over 60 s, far outside
                    // the fit's basin.
                    {"f", 1e-4, ripple_hz, ripple_hz, ripple_hz},
                    {"", 1e5, 0.0, -5e6, 5e6}},
                   {}});
  }
  out.push_back({"supply_droop", "", {sized({"R_s", 1e10, 5e9, -5e9, 3e11}, k.droop)}, {}});
  out.back().size = k.droop;
  for (const char* channel : {"p1", "p2"}) {
    out.push_back({"sensor_offset", channel, {{"offset", 1e5, 0.0, -3e6, 3e6}}, {}});
  }
  for (const char* channel : {"p1", "p2"}) {
    out.push_back({"sensor_lag", channel, {{"tau_s", 0.002, 0.004, 5e-4, 0.1}}, {}});
  }
  if (has_temperature) {
    out.push_back({"oil_temperature", "", {{"visc_slope", 0.01, 0.045, 0.0, 0.12}}, {}});
  }
  for (auto& candidate : out) {
    candidate.sample_period = sample_period;
    candidate.rig_spool_tau = tau;
  }
  return out;
}

}  // namespace leakmon::model
