#include "sim/scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "config/yaml_reader.hpp"

namespace leakmon::sim {
namespace {

// MODEL.md's effect table converts leak sizes quoted in l/min/MPa: 1 l/min = 1/60000 m^3/s.
constexpr double kLitresPerMinutePerMPa = 1.0 / 60000.0 / 1e6;

struct NumberSpec {
  std::string_view name;
  double lo, hi;
};

// Parameter names with physically meaningful bounds (wider than MODEL.md's "measured data"
// ranges: the model check must also handle values outside those).
struct EffectSpec {
  std::string_view name;
  std::vector<NumberSpec> numbers;
  bool has_channel = false;  // sensor effects: channel p1 or p2
};

const std::vector<EffectSpec>& effect_specs() {
  static const std::vector<EffectSpec> specs = {
      {"internal_leakage", {{"C_L", 0.0, 1e-9}, {"onset_s", 0.0, 1e7}, {"ramp_s", 0.0, 1e4}}},
      {"external_leakage", {{"C_E", 0.0, 1e-9}, {"chamber", 1.0, 2.0}}},
      {"coulomb_friction", {{"F_C", 0.0, 1e4}}},
      {"entrained_air", {{"alpha", 0.0, 1.0}}},
      {"valve_overlap", {{"d", 0.0, 0.5}}},
      {"valve_bias", {{"u0", -10.0, 10.0}}},
      {"spool_lag", {{"tau", 1e-4, 1.0}}},
      {"supply_ripple", {{"dP", 0.0, 1e7}, {"f", 0.0, 1000.0}}},
      {"supply_droop", {{"R_s", 0.0, 1e12}}},
      {"sensor_offset", {{"offset", -2e7, 2e7}}, true},
      {"sensor_lag", {{"tau_s", 1e-4, 1.0}}, true},
  };
  return specs;
}

const std::vector<NumberSpec>& parameter_specs() {
  static const std::vector<NumberSpec> specs = {
      {"D", 1e-3, 1.0},      {"d", 0.0, 1.0},       {"L", 1e-3, 10.0},    {"V_dead", 1e-7, 1e-1},
      {"V_line", 0.0, 1e-1}, {"ps", 1e5, 1e8},      {"pt", 0.0, 1e6},     {"beta", 1e7, 1e10},
      {"m", 0.1, 1e4},       {"b", 0.0, 1e5},       {"K_s", 0.0, 1e8},    {"Kv", 1e-10, 1e-4},
      {"tau", 1e-4, 1.0},    {"u_max", 0.1, 100.0}, {"dp_lin", 1.0, 1e7}, {"C_n", 0.0, 1e-9},
      {"sigma_w", 0.0, 0.1}, {"tau_w", 1e-5, 1.0},  {"K_stop", 1e3, 1e9}, {"c_stop", 0.0, 1e6},
  };
  return specs;
}

double& parameter(Parameters& p, std::string_view name) {
  if (name == "D") return p.D;
  if (name == "d") return p.d;
  if (name == "L") return p.L;
  if (name == "V_dead") return p.V_dead;
  if (name == "V_line") return p.V_line;
  if (name == "ps") return p.ps;
  if (name == "pt") return p.pt;
  if (name == "beta") return p.beta;
  if (name == "m") return p.m;
  if (name == "b") return p.b;
  if (name == "K_s") return p.K_s;
  if (name == "Kv") return p.Kv;
  if (name == "tau") return p.tau;
  if (name == "u_max") return p.u_max;
  if (name == "dp_lin") return p.dp_lin;
  if (name == "C_n") return p.C_n;
  if (name == "sigma_w") return p.sigma_w;
  if (name == "tau_w") return p.tau_w;
  if (name == "K_stop") return p.K_stop;
  return p.c_stop;
}

template <typename Specs>
std::vector<std::string> spec_names(const Specs& specs) {
  std::vector<std::string> names;
  for (const auto& spec : specs) names.emplace_back(spec.name);
  return names;
}

void read_parameters(const config::ConfigNode& node, Parameters& params) {
  node.expect_keys(spec_names(parameter_specs()));
  for (const auto& spec : parameter_specs()) {
    double& value = parameter(params, spec.name);
    value = node.get_double(spec.name, value, spec.lo, spec.hi);
  }
  if (params.d >= params.D) node.at("d").fail("rod diameter d must be smaller than the bore D");
}

void read_effects(const config::ConfigNode& node, Effects& effects) {
  node.expect_keys(spec_names(effect_specs()));
  for (const auto& spec : effect_specs()) {
    const auto effect = node.find(spec.name);
    if (!effect) continue;
    std::vector<std::string> allowed = spec_names(spec.numbers);
    if (spec.has_channel) allowed.emplace_back("channel");
    effect->expect_keys(allowed);
    std::vector<EffectParameter> params;
    for (const auto& number : spec.numbers) {
      if (!effect->has(number.name)) continue;
      double value = effect->get_double(number.name, number.lo, number.hi);
      if (number.name == "chamber" && value != std::round(value)) {
        effect->at("chamber").fail("chamber must be 1 or 2");
      }
      params.push_back({std::string(number.name), value});
    }
    if (spec.has_channel && effect->has("channel")) {
      params.push_back({"channel", effect->get_choice("channel", {"p1", "p2"}, "p1")});
    }
    try {
      effects.enable(spec.name, params);
    } catch (const EffectError& e) {
      effect->fail(e.what());
    }
  }
}

void read_reference(const config::ConfigNode& node, ReferenceSettings& reference) {
  node.expect_keys({"amp_min", "amp_max", "hold_min", "hold_max"});
  reference.amp_min = node.get_double("amp_min", reference.amp_min, 0.0, 1.0);
  reference.amp_max = node.get_double("amp_max", reference.amp_max, 0.0, 1.0);
  reference.hold_min = node.get_double("hold_min", reference.hold_min, 1e-3, 1e5);
  reference.hold_max = node.get_double("hold_max", reference.hold_max, 1e-3, 1e5);
  if (reference.amp_max < reference.amp_min) node.fail("amp_max must not be below amp_min");
  if (reference.hold_max < reference.hold_min) node.fail("hold_max must not be below hold_min");
}

void read_sensors(const config::ConfigNode& node, SensorSettings& sensors) {
  node.expect_keys({"enabled", "pressure_quantisation", "pressure_full_scale", "pressure_bits",
                    "pressure_noise_sigma", "position_quantisation", "position_resolution",
                    "position_noise_sigma"});
  sensors.enabled = node.get_bool("enabled", sensors.enabled);
  sensors.pressure_quantisation =
      node.get_bool("pressure_quantisation", sensors.pressure_quantisation);
  sensors.pressure_full_scale =
      node.get_double("pressure_full_scale", sensors.pressure_full_scale, 1e5, 1e9);
  sensors.pressure_bits =
      static_cast<int>(node.get_int("pressure_bits", sensors.pressure_bits, 1, 32));
  sensors.pressure_noise_sigma =
      node.get_double("pressure_noise_sigma", sensors.pressure_noise_sigma, 0.0, 1e7);
  sensors.position_quantisation =
      node.get_bool("position_quantisation", sensors.position_quantisation);
  sensors.position_resolution =
      node.get_double("position_resolution", sensors.position_resolution, 1e-9, 1e-1);
  sensors.position_noise_sigma =
      node.get_double("position_noise_sigma", sensors.position_noise_sigma, 0.0, 1e-1);
}

Scenario read_scenario(const config::ConfigNode& root) {
  root.expect_keys({"name", "controller", "duration_s", "seed", "sample_rate_hz",
                    "integration_step_s", "reference", "params", "effects", "sensors"});
  Scenario scenario;
  scenario.name = root.get_string("name", "scenario");
  scenario.controller = controller_kind_from_string(
      root.get_choice("controller", {"basic", "fault_tolerant"}, "basic"));
  scenario.duration_s = root.get_double("duration_s", scenario.duration_s, 0.002, 1e6);
  scenario.seed = static_cast<std::uint64_t>(root.get_int("seed", 1, 0, (1LL << 62)));
  scenario.sample_rate_hz = root.get_double("sample_rate_hz", 500.0, 50.0, 1e5);
  if (auto node = root.find("reference")) read_reference(*node, scenario.reference);
  if (auto node = root.find("params")) read_parameters(*node, scenario.params);
  if (auto node = root.find("effects")) read_effects(*node, scenario.effects);
  if (auto node = root.find("sensors")) read_sensors(*node, scenario.sensors);
  if (auto node = root.find("integration_step_s")) {
    const double period = 1.0 / scenario.sample_rate_hz;
    const double h = node->as_double();
    node->check_range(h, 0.0, period);
    const double per_sample = h > 0.0 ? period / h : 1.0;
    if (h > 0.0 && std::abs(per_sample - std::round(per_sample)) > 1e-6) {
      node->fail(fmt::format("must divide the sample period {:g} s (e.g. {:g})", period,
                             period / std::ceil(per_sample)));
    }
    scenario.integration_step_s = h;
  }
  return scenario;
}

Scenario paper_experiment(std::string_view name, ControllerKind controller, double duration_s,
                          double onset_s, double leak_lpm_per_mpa, std::uint64_t seed) {
  Scenario s;
  s.name = std::string(name);
  s.origin = "preset " + s.name;
  s.controller = controller;
  s.duration_s = duration_s;
  s.seed = seed;
  s.effects.internal_leakage =
      InternalLeakage{leak_lpm_per_mpa * kLitresPerMinutePerMPa, onset_s, 0.0};
  return s;
}

}  // namespace

std::uint64_t Scenario::samples() const {
  return static_cast<std::uint64_t>(std::llround(duration_s * sample_rate_hz));
}

double integration_step(const Scenario& scenario) {
  if (scenario.integration_step_s > 0.0) return scenario.integration_step_s;
  return automatic_integration_step(scenario.params, scenario.effects, scenario.sample_rate_hz);
}

Scenario parse_scenario(const std::string& yaml_text, const std::string& source_name) {
  Scenario s = read_scenario(config::ConfigNode::load_string(yaml_text, source_name));
  s.origin = "scenario " + source_name;
  return s;
}

Scenario load_scenario(const std::string& path) {
  Scenario s = read_scenario(config::ConfigNode::load_file(path));
  s.origin = "scenario " + path;
  return s;
}

Scenario preset(std::string_view name, std::uint64_t seed) {
  // MODEL.md "Paper experiments to reproduce".
  if (name == "paper-fig10") {
    return paper_experiment(name, ControllerKind::basic, 30.0, 15.0, 0.12, seed);
  }
  if (name == "paper-fig13") {
    return paper_experiment(name, ControllerKind::basic, 600.0, 300.0, 0.13, seed);
  }
  if (name == "paper-fig16") {
    return paper_experiment(name, ControllerKind::fault_tolerant, 600.0, 300.0, 0.149, seed);
  }
  if (name == "healthy" || name == "healthy-ft") {
    Scenario s;
    s.name = std::string(name);
    s.origin = "preset " + s.name;
    s.controller = name == "healthy" ? ControllerKind::basic : ControllerKind::fault_tolerant;
    s.duration_s = 60.0;
    s.seed = seed;
    return s;
  }
  throw std::invalid_argument(
      fmt::format("unknown preset '{}' (presets: {})", name, fmt::join(preset_names(), ", ")));
}

std::vector<std::string> preset_names() {
  return {"paper-fig10", "paper-fig13", "paper-fig16", "healthy", "healthy-ft"};
}

}  // namespace leakmon::sim
