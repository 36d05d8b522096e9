#include "sim/scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "capture/units.hpp"
#include "config/yaml_reader.hpp"

namespace leakmon::sim {
namespace {

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
      // ramp_s: from a needle valve opened by hand (a second) to a seal that wears (hours).
      {"internal_leakage", {{"C_L", 0.0, 1e-9}, {"onset_s", 0.0, 1e7}, {"ramp_s", 0.0, 1e6}}},
      {"external_leakage",
       {{"C_E", 0.0, 1e-9}, {"chamber", 1.0, 2.0}, {"onset_s", 0.0, 1e7}, {"ramp_s", 0.0, 1e6}}},
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

void read_parameters(const config::ConfigNode& node, const RigDescription& rig,
                     Parameters& params) {
  node.expect_keys(spec_names(parameter_specs()));
  for (const auto& spec : parameter_specs()) {
    if (rig.states_symbol(spec.name) && node.has(spec.name)) {
      node.at(spec.name).fail(fmt::format(
          "{} is also stated in the scenario's rig: ({}); give it once", spec.name, rig.source));
    }
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

// MODEL.md "Test programs": `- {phase: sine, F: 0.5, A: 0.02, duration_s: 240}`, the values
// named by MODEL.md's symbols; every phase but the last needs its length.
std::vector<Phase> read_program(const config::ConfigNode& node, const Parameters& params) {
  if (!node.is_sequence() || node.items().empty()) {
    node.fail(
        "must be a list of phases {phase: steps|hold|sine|sweep|triangle, their values, "
        "duration_s}");
  }
  const double half_stroke = 0.5 * params.L;
  const auto inside_stroke = [&](const config::ConfigNode& item, std::string_view key,
                                 double value) {
    if (std::abs(value) >= half_stroke) {
      item.at(key).fail(fmt::format("{} must stay inside the stroke (|{}| < L/2 = {:g} m)", key,
                                    key, half_stroke));
    }
  };
  std::vector<Phase> program;
  const auto items = node.items();
  for (std::size_t i = 0; i < items.size(); ++i) {
    const config::ConfigNode& item = items[i];
    if (!item.is_map()) item.fail("a phase is a mapping {phase: KIND, its values, duration_s}");
    if (!item.has("phase")) item.fail("phase is required (steps, hold, sine, sweep or triangle)");
    Phase phase;
    phase.kind = *phase_kind_from_string(
        item.get_choice("phase", {"steps", "hold", "sine", "sweep", "triangle"}, "steps"));
    switch (phase.kind) {
      case PhaseKind::steps:
        item.expect_keys({"phase", "duration_s"});
        break;
      case PhaseKind::hold:
        item.expect_keys({"phase", "X", "duration_s"});
        phase.X = item.get_double("X", -10.0, 10.0);
        inside_stroke(item, "X", phase.X);
        break;
      case PhaseKind::sine:
        item.expect_keys({"phase", "F", "A", "duration_s"});
        phase.F = item.get_double("F", 1e-4, 100.0);
        phase.A = item.get_double("A", 0.0, 10.0);
        break;
      case PhaseKind::sweep:
        item.expect_keys({"phase", "F0", "F1", "A", "duration_s"});
        phase.F0 = item.get_double("F0", 0.0, 100.0);
        phase.F1 = item.get_double("F1", 0.0, 100.0);
        phase.A = item.get_double("A", 0.0, 10.0);
        break;
      case PhaseKind::triangle:
        item.expect_keys({"phase", "P", "A", "duration_s"});
        phase.P = item.get_double("P", 1e-3, 1e5);
        phase.A = item.get_double("A", 0.0, 10.0);
        break;
    }
    if (phase.kind != PhaseKind::steps && phase.kind != PhaseKind::hold) {
      inside_stroke(item, "A", phase.A);
    }
    const bool last = i + 1 == items.size();
    if (!last && !item.has("duration_s")) {
      item.fail("duration_s is required for every phase but the last (which runs to the end)");
    }
    // A sweep needs its T; the last phase's defaults to the rest of the run.
    phase.duration_s = item.has("duration_s") ? item.get_double("duration_s", 0.002, 1e7) : 0.0;
    program.push_back(phase);
  }
  return program;
}

void read_sensors(const config::ConfigNode& node, SensorSettings& sensors) {
  node.expect_keys({"enabled", "pressure_quantisation", "pressure_full_scale", "pressure_bits",
                    "pressure_noise_sigma", "position_quantisation", "position_resolution",
                    "position_noise_sigma", "temp_resolution", "temp_noise_sigma"});
  sensors.temp_resolution = node.get_double("temp_resolution", sensors.temp_resolution, 1e-4, 10.0);
  sensors.temp_noise_sigma =
      node.get_double("temp_noise_sigma", sensors.temp_noise_sigma, 0.0, 10.0);
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

Oil read_oil(const config::ConfigNode& node) {
  node.expect_keys({"grade", "nu40", "nu100"});
  if (node.has("grade")) {
    if (node.has("nu40") || node.has("nu100")) node.fail("give either grade or nu40 and nu100");
    const auto grade = node.at("grade");
    const auto oil = Oil::iso_vg(static_cast<int>(grade.as_int()));
    if (!oil) grade.fail("ISO VG grade must be 32, 46 or 68 (or give nu40 and nu100)");
    return *oil;
  }
  const double nu40 = node.get_double("nu40", 1.0, 1e4);
  const double nu100 = node.get_double("nu100", 0.5, 1e4);
  if (!(nu100 < nu40)) node.at("nu100").fail("nu100 must be below nu40");
  return Oil(nu40, nu100);
}

TemperatureProfile read_temperature(const config::ConfigNode& node) {
  using Kind = TemperatureProfile::Kind;
  TemperatureProfile t;
  const std::string profile =
      node.get_choice("profile", {"constant", "warm_up", "cooler", "warm_up_cooler"}, "constant");
  if (profile == "constant") {
    node.expect_keys({"profile", "T"});
    t.kind = Kind::constant;
    t.T_work = node.get_double("T", kReferenceTemperature, -30.0, 150.0);
    return t;
  }
  const bool warm = profile == "warm_up" || profile == "warm_up_cooler";
  const bool cool = profile == "cooler" || profile == "warm_up_cooler";
  std::vector<std::string> keys = {"profile", "T_work"};
  if (warm) keys.insert(keys.end(), {"T0", "tau_s", "start_s"});
  if (cool) keys.insert(keys.end(), {"amplitude", "period_s", "cooler_start_s"});
  node.expect_keys(keys);
  t.kind = profile == "warm_up"  ? Kind::warm_up
           : profile == "cooler" ? Kind::cooler
                                 : Kind::warm_up_cooler;
  t.T_work = node.get_double("T_work", 50.0, -30.0, 150.0);
  if (warm) {
    t.T0 = node.get_double("T0", 20.0, -30.0, 150.0);
    t.tau_s = node.get_double("tau_s", 600.0, 1.0, 1e6);
    t.start_s = node.get_double("start_s", 0.0, 0.0, 1e7);
  }
  if (cool) {
    t.amplitude = node.get_double("amplitude", 2.0, 0.0, 30.0);
    t.period_s = node.get_double("period_s", 600.0, 1.0, 1e6);
    t.cooler_start_s = node.get_double(
        "cooler_start_s", profile == "warm_up_cooler" ? t.start_s + 3.0 * t.tau_s : 0.0, 0.0, 1e7);
  }
  if (t.minimum() < -30.0 || t.T_work + t.amplitude > 150.0) {
    node.fail("the profile leaves -30..150 degC");
  }
  return t;
}

std::vector<SupplyChange> read_supply(const config::ConfigNode& node) {
  if (!node.is_sequence()) node.fail("must be a list of {t_s, ps, ramp_s}");
  std::vector<SupplyChange> changes;
  for (const auto& item : node.items()) {
    item.expect_keys({"t_s", "ps", "ramp_s"});
    SupplyChange change;
    change.t_s = item.get_double("t_s", 0.0, 1e7);
    change.ps = item.get_double("ps", 1e5, 1e8);
    change.ramp_s = item.get_double("ramp_s", 0.0, 0.0, 1e5);
    if (!changes.empty() && change.t_s < changes.back().t_s + changes.back().ramp_s) {
      item.at("t_s").fail("changes must be in time order and must not overlap the previous ramp");
    }
    changes.push_back(change);
  }
  return changes;
}

void read_conditions(const config::ConfigNode& node, const RigDescription& rig,
                     OperatingConditions& conditions) {
  node.expect_keys({"oil", "temperature", "supply"});
  if (auto oil = node.find("oil")) {
    if (rig.states_symbol("oil")) {
      oil->fail(fmt::format("the oil is also stated in the scenario's rig: ({}); give it once",
                            rig.source));
    }
    conditions.oil = read_oil(*oil);
  }
  if (auto temperature = node.find("temperature")) {
    conditions.temperature = read_temperature(*temperature);
  }
  if (auto supply = node.find("supply")) conditions.supply = read_supply(*supply);
}

Scenario::Record read_record(const config::ConfigNode& node) {
  if (!node.is_sequence()) node.fail("must be a list of optional columns: ps, temp");
  Scenario::Record record;
  for (const auto& item : node.items()) {
    const std::string column = item.as_string();
    if (column == "ps") {
      record.ps = true;
    } else if (column == "temp") {
      record.temp = true;
    } else {
      item.fail(fmt::format("unknown optional column '{}' (allowed: ps, temp)", column));
    }
  }
  return record;
}

std::vector<SensorFault> read_faults(const config::ConfigNode& node,
                                     const Scenario::Record& record) {
  if (!node.is_sequence()) node.fail("must be a list of {type, channel, start_s, ...}");
  std::vector<SensorFault> faults;
  for (const auto& item : node.items()) {
    SensorFault fault;
    const std::string type =
        item.get_choice("type", {"frozen", "saturated", "spikes", "dropout"}, "frozen");
    if (!item.has("type")) item.fail("type is required (frozen, saturated, spikes or dropout)");
    std::vector<std::string> keys = {"type", "channel", "start_s", "duration_s"};
    if (type == "saturated") keys.emplace_back("level");
    if (type == "spikes") keys.insert(keys.end(), {"rate_per_min", "magnitude"});
    if (type == "dropout") keys.emplace_back("mode");
    item.expect_keys(keys);
    fault.kind = type == "frozen"      ? SensorFault::Kind::frozen
                 : type == "saturated" ? SensorFault::Kind::saturated
                 : type == "spikes"    ? SensorFault::Kind::spikes
                                       : SensorFault::Kind::dropout;
    if (!item.has("channel")) item.fail("channel is required (p1, p2, x, ps or temp)");
    const std::string channel = item.get_choice("channel", {"p1", "p2", "x", "ps", "temp"}, "p1");
    fault.channel = channel == "p1"   ? SensorChannel::p1
                    : channel == "p2" ? SensorChannel::p2
                    : channel == "x"  ? SensorChannel::x
                    : channel == "ps" ? SensorChannel::ps
                                      : SensorChannel::temp;
    if ((fault.channel == SensorChannel::ps && !record.ps) ||
        (fault.channel == SensorChannel::temp && !record.temp)) {
      item.at("channel").fail(
          fmt::format("channel {} is not recorded: add it to the scenario's record list", channel));
    }
    fault.start_s = item.get_double("start_s", 0.0, 0.0, 1e7);
    if (item.has("duration_s")) fault.duration_s = item.get_double("duration_s", 0.002, 1e7);
    if (type == "saturated") {
      fault.high = item.get_choice("level", {"high", "low"}, "high") == "high";
    }
    if (type == "spikes") {
      fault.rate_per_min = item.get_double("rate_per_min", fault.rate_per_min, 0.0, 3000.0);
      const bool pressure = fault.channel == SensorChannel::p1 ||
                            fault.channel == SensorChannel::p2 ||
                            fault.channel == SensorChannel::ps;
      // Defaults in the channel's unit: 3 MPa, 5 mm, 20 K.
      const double fallback = pressure ? 3e6 : fault.channel == SensorChannel::x ? 5e-3 : 20.0;
      fault.magnitude = item.get_double("magnitude", fallback, 0.0, pressure ? 1e8 : 1e3);
    }
    if (type == "dropout") fault.gap = item.get_choice("mode", {"zero", "gap"}, "zero") == "gap";
    faults.push_back(fault);
  }
  return faults;
}

// The reference against what the rig can do (reference_reach): an error beyond the end stops
// or nearly all of the rig's force, a warning where tracking suffers. Reported at the
// reference's amp_max when given, else at the rig (or params) that makes it too much.
void check_reach(const config::ConfigNode& root, Scenario& scenario) {
  const ReferenceReach reach = reference_reach(scenario.params, scenario.reference);
  std::optional<config::ConfigNode> at;
  if (auto reference = root.find("reference")) at = reference->find("amp_max");
  if (!at) at = root.find("rig");
  if (!at) at = root.find("params");
  if (!at) at = root;
  const double amplitude_mm = scenario.reference.amp_max * 1e3;
  const std::string stroke =
      fmt::format("the reference's steps reach {:.4g} mm, {:.0f} % of the half stroke ({:.4g} mm)",
                  amplitude_mm, 100.0 * reach.stroke_share, scenario.params.L * 500.0);
  const std::string force = fmt::format(
      "the load spring needs {:.4g} kN at the reference's largest step ({:.4g} mm), {:.0f} % of "
      "the {:.4g} kN the piston can make (A (ps - pt))",
      scenario.params.K_s * scenario.reference.amp_max * 1e-3, amplitude_mm,
      100.0 * reach.force_share,
      scenario.params.A() * (scenario.params.ps - scenario.params.pt) * 1e-3);
  if (reach.stroke_share >= kStrokeShareError) {
    at->fail(stroke + ": beyond the end stops; lower reference.amp_max or state the stroke");
  }
  if (reach.force_share > kForceShareError) {
    at->fail(force + ": the rig cannot follow it; lower reference.amp_max");
  }
  if (reach.stroke_share > kStrokeShareWarning) {
    scenario.warnings.push_back(
        fmt::format("{}: {}: overshoot may hit the end stops", at->location(), stroke));
  }
  if (reach.force_share > kForceShareWarning) {
    scenario.warnings.push_back(fmt::format(
        "{}: {}: above about half the rig tracks the steps poorly (MODEL.md \"Other rigs\")",
        at->location(), force));
  }
}

Scenario read_scenario(const config::ConfigNode& root) {
  root.expect_keys({"name", "controller", "duration_s", "seed", "sample_rate_hz",
                    "integration_step_s", "reference", "program", "rig", "params", "effects",
                    "sensors", "conditions", "faults", "record"});
  Scenario scenario;
  scenario.name = root.get_string("name", "scenario");
  scenario.controller = controller_kind_from_string(
      root.get_choice("controller", {"basic", "fault_tolerant"}, "basic"));
  scenario.duration_s = root.get_double("duration_s", scenario.duration_s, 0.002, 1e6);
  scenario.seed = static_cast<std::uint64_t>(root.get_int("seed", 1, 0, (1LL << 62)));
  scenario.sample_rate_hz = root.get_double("sample_rate_hz", 500.0, 50.0, 1e5);
  if (auto node = root.find("reference")) read_reference(*node, scenario.reference);
  if (auto node = root.find("rig")) {
    scenario.rig = read_rig(*node);
    scenario.params = scenario.rig.params;
    scenario.conditions.oil = scenario.rig.oil;
    // The transducers a rig with this supply is fitted with, unless `sensors:` says otherwise
    // (the paper's 20.7 MPa for its 17.2 MPa).
    if (scenario.rig.states("supply_pressure")) {
      scenario.sensors.pressure_full_scale = sensors_for(scenario.rig.params).pressure_full_scale;
    }
  }
  if (auto node = root.find("params")) read_parameters(*node, scenario.rig, scenario.params);
  if (auto node = root.find("program")) scenario.program = read_program(*node, scenario.params);
  if (auto node = root.find("effects")) read_effects(*node, scenario.effects);
  if (auto node = root.find("sensors")) read_sensors(*node, scenario.sensors);
  check_reach(root, scenario);
  if (auto node = root.find("conditions")) {
    read_conditions(*node, scenario.rig, scenario.conditions);
  }
  if (auto node = root.find("record")) scenario.record = read_record(*node);
  if (auto node = root.find("faults")) scenario.faults = read_faults(*node, scenario.record);
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
      InternalLeakage{units::cubic_metres_per_second_pascal(leak_lpm_per_mpa), onset_s, 0.0};
  return s;
}

}  // namespace

ReferenceReach reference_reach(const Parameters& params, const ReferenceSettings& reference) {
  ReferenceReach reach;
  reach.stroke_share = reference.amp_max / (0.5 * params.L);
  reach.force_share = params.K_s * reference.amp_max / (params.A() * (params.ps - params.pt));
  return reach;
}

std::uint64_t Scenario::samples() const {
  return static_cast<std::uint64_t>(std::llround(duration_s * sample_rate_hz));
}

double integration_step(const Scenario& scenario) {
  // Drifting conditions do not change the step: cold oil stiffens the hydraulic mode by
  // 0.3 %/K, which at -30 degC puts the default step at h |lambda| = 2.3, still inside RK4's
  // stability limit of 2.78; shortening it to a step that is not a divisor of the flow noise
  // grid would cost more accuracy than it gains (docs/simulation.md).
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
