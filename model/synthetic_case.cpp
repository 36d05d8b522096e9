#include "model/synthetic_case.hpp"

#include <fmt/format.h>

#include <random>

#include "model/effect_library.hpp"
#include "sim/simulate.hpp"

namespace leakmon::model {
namespace {

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(engine_); }
  // Log-uniform: leak sizes and resistances span an order of magnitude.
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  double sign() { return uniform(0.0, 1.0) < 0.5 ? -1.0 : 1.0; }
  bool coin() { return uniform(0.0, 1.0) < 0.5; }
  std::size_t index(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(engine_);
  }
  std::uint64_t seed() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

}  // namespace

SyntheticCase draw_case(std::uint64_t seed, const std::string& effect,
                        const CaseSettings& settings) {
  Draw draw(seed);
  SyntheticCase c;
  c.seed = seed;
  const auto& names = effect_names();
  if (effect.empty()) {
    const std::size_t i = draw.index(names.size() + 1);
    c.effect = i < names.size() ? names[i] : "none";
  } else {
    c.effect = effect;
  }
  auto& s = c.scenario;
  s.name = fmt::format("model-check case {} ({})", seed, c.effect);
  s.origin = fmt::format("model check synthetic case seed {}", seed);
  s.controller = draw.coin() ? sim::ControllerKind::basic : sim::ControllerKind::fault_tolerant;
  s.duration_s = settings.duration_s;
  s.seed = draw.seed();
  // Calibratable parameters within MODEL.md's ranges: not a discrepancy to report.
  s.params.beta *= draw.uniform(0.75, 1.25);
  s.params.Kv *= draw.uniform(0.9, 1.1);
  s.params.m *= draw.uniform(0.8, 1.2);
  s.params.b *= draw.uniform(0.7, 1.3);

  auto& e = s.effects;
  const auto set_main = [&](const char* name, double value) {
    c.main_parameter = name;
    c.main_value = value;
    return value;
  };
  const auto channel = [&] {
    return draw.coin() ? sim::PressureChannel::p1 : sim::PressureChannel::p2;
  };
  if (c.effect == "internal_leakage") {
    e.internal_leakage = sim::InternalLeakage{set_main("C_L", draw.log_uniform(5e-13, 5e-12))};
  } else if (c.effect == "external_leakage") {
    const double ce = set_main("C_E", draw.log_uniform(1e-13, 2e-12));
    e.external_leakage = sim::ExternalLeakage{ce, draw.coin() ? 1 : 2};
  } else if (c.effect == "coulomb_friction") {
    e.coulomb_friction = sim::CoulombFriction{set_main("F_C", draw.uniform(50.0, 400.0))};
  } else if (c.effect == "entrained_air") {
    e.entrained_air = sim::EntrainedAir{set_main("alpha", draw.log_uniform(0.02, 0.2))};
  } else if (c.effect == "valve_overlap") {
    e.valve_overlap = sim::ValveOverlap{set_main("d", draw.uniform(0.01, 0.05))};
  } else if (c.effect == "valve_bias") {
    e.valve_bias = sim::ValveBias{set_main("u0", draw.sign() * draw.uniform(0.05, 0.3))};
  } else if (c.effect == "spool_lag") {
    e.spool_lag = sim::SpoolLag{set_main("tau", draw.uniform(0.006, 0.015))};
  } else if (c.effect == "supply_ripple") {
    const double dp = set_main("dP", draw.uniform(2e5, 1e6));
    e.supply_ripple = sim::SupplyRipple{dp, draw.uniform(20.0, 200.0)};
  } else if (c.effect == "supply_droop") {
    e.supply_droop = sim::SupplyDroop{set_main("R_s", draw.log_uniform(5e9, 3e10))};
  } else if (c.effect == "sensor_offset") {
    const double offset = set_main("offset", draw.sign() * draw.uniform(5e4, 3e5));
    e.sensor_offset = sim::SensorOffset{offset, channel()};
  } else if (c.effect == "sensor_lag") {
    e.sensor_lag = sim::SensorLag{set_main("tau_s", draw.uniform(0.002, 0.01)), channel()};
  } else if (c.effect != "none") {
    throw std::invalid_argument(fmt::format("unknown effect '{}'", c.effect));
  }
  return c;
}

capture::Capture simulate_case(const SyntheticCase& c) { return sim::simulate(c.scenario); }

}  // namespace leakmon::model
