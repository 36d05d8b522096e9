// Scenario files and presets: the examples in sim/scenarios/ load and run; bad input fails
// with file:line:column and the field's path; presets carry MODEL.md's experiment table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "config/yaml_reader.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::sim {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_scenario(yaml, "bad.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ScenarioFiles, EveryExampleLoadsAndRuns) {
  int count = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(test::source_dir() + "/sim/scenarios")) {
    if (entry.path().extension() != ".yaml") continue;
    Scenario s = load_scenario(entry.path().string());
    EXPECT_FALSE(s.name.empty());
    EXPECT_NE(s.origin.find(entry.path().filename().string()), std::string::npos);
    s.duration_s = 1.0;
    const capture::Capture capture = simulate(s);
    EXPECT_EQ(capture.rows(), 500u) << entry.path();
    ++count;
  }
  EXPECT_GE(count, 5);
}

TEST(ScenarioFiles, ReadEveryField) {
  const Scenario s = parse_scenario(R"(name: all
controller: fault_tolerant
duration_s: 12.5
seed: 77
sample_rate_hz: 500
integration_step_s: 1.0e-4
reference: {amp_min: 0.01, amp_max: 0.02, hold_min: 1, hold_max: 2}
params: {beta: 6.0e8, Kv: 3.5e-7, m: 9, b: 250, sigma_w: 0.001}
effects:
  internal_leakage: {C_L: 1.0e-12, onset_s: 4, ramp_s: 0.5}
  external_leakage: {C_E: 3.0e-13, chamber: 2}
  sensor_lag: {tau_s: 0.003, channel: p2}
  supply_ripple: {dP: 3.0e5, f: 45}
sensors: {enabled: true, pressure_noise_sigma: 2000, position_quantisation: false}
)",
                                    "all.yaml");
  EXPECT_EQ(s.controller, ControllerKind::fault_tolerant);
  EXPECT_EQ(s.duration_s, 12.5);
  EXPECT_EQ(s.seed, 77u);
  EXPECT_EQ(s.samples(), 6250u);
  EXPECT_EQ(integration_step(s), 1.0e-4);
  EXPECT_EQ(s.reference.amp_max, 0.02);
  EXPECT_EQ(s.params.beta, 6.0e8);
  EXPECT_EQ(s.params.sigma_w, 0.001);
  EXPECT_EQ(s.params.K_s, Parameters::nominal().K_s);
  ASSERT_TRUE(s.effects.internal_leakage);
  EXPECT_EQ(s.effects.internal_leakage->ramp_s, 0.5);
  ASSERT_TRUE(s.effects.external_leakage);
  EXPECT_EQ(s.effects.external_leakage->chamber, 2);
  ASSERT_TRUE(s.effects.sensor_lag);
  EXPECT_EQ(s.effects.sensor_lag->channel, PressureChannel::p2);
  EXPECT_EQ(s.effects.supply_ripple->f, 45.0);
  EXPECT_FALSE(s.effects.coulomb_friction);
  EXPECT_EQ(s.sensors.pressure_noise_sigma, 2000.0);
  EXPECT_FALSE(s.sensors.position_quantisation);
  EXPECT_EQ(s.effects.describe().size(), 4u);
}

TEST(ScenarioErrors, NameFileLineColumnAndField) {
  // Unknown top-level key, with the keys that are allowed.
  std::string e = error_of("name: x\ndurration_s: 5\n");
  EXPECT_NE(e.find("bad.yaml:2:1"), std::string::npos) << e;
  EXPECT_NE(e.find("durration_s"), std::string::npos) << e;
  EXPECT_NE(e.find("duration_s"), std::string::npos) << e;
  // Out-of-range effect parameter.
  e = error_of("effects:\n  internal_leakage: {C_L: -1.0e-12}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("C_L"), std::string::npos) << e;
  // Unknown effect parameter.
  e = error_of("effects:\n  coulomb_friction:\n    F_c: 100\n");
  EXPECT_NE(e.find("bad.yaml:3:5"), std::string::npos) << e;
  EXPECT_NE(e.find("F_c"), std::string::npos) << e;
  // Unknown effect.
  e = error_of("effects:\n  cavitation: {}\n");
  EXPECT_NE(e.find("bad.yaml:2:3"), std::string::npos) << e;
  EXPECT_NE(e.find("cavitation"), std::string::npos) << e;
  // Channel must be p1 or p2.
  e = error_of("effects:\n  sensor_offset: {offset: 1.0e5, channel: p3}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("p3"), std::string::npos) << e;
  // Wrong type.
  e = error_of("params:\n  beta: stiff\n");
  EXPECT_NE(e.find("bad.yaml:2:9"), std::string::npos) << e;
  EXPECT_NE(e.find("beta"), std::string::npos) << e;
  // Parameter out of range.
  e = error_of("params: {m: 0}\n");
  EXPECT_NE(e.find("bad.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("params.m"), std::string::npos) << e;
  // Geometry that cannot exist.
  e = error_of("params: {D: 0.03, d: 0.04}\n");
  EXPECT_NE(e.find("rod diameter"), std::string::npos) << e;
  // An integration step that does not divide the sample period.
  e = error_of("integration_step_s: 3.0e-4\n");
  EXPECT_NE(e.find("bad.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("divide"), std::string::npos) << e;
  // Unknown controller.
  e = error_of("controller: pid\n");
  EXPECT_NE(e.find("bad.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("fault_tolerant"), std::string::npos) << e;
  // Reference ranges the wrong way round.
  e = error_of("reference: {amp_min: 0.05, amp_max: 0.02}\n");
  EXPECT_NE(e.find("amp_max"), std::string::npos) << e;
}

TEST(ScenarioFiles, ReadConditionsFaultsAndRecordedColumns) {
  const Scenario s = parse_scenario(R"(name: drift
effects:
  external_leakage: {C_E: 4.0e-13, chamber: 1, onset_s: 30, ramp_s: 2}
conditions:
  oil: {grade: 68}
  temperature: {profile: warm_up_cooler, T0: 18, T_work: 52, tau_s: 300, start_s: 10,
                amplitude: 3, period_s: 400}
  supply:
    - {t_s: 120, ps: 1.4e7, ramp_s: 2}
    - {t_s: 200, ps: 1.8e7}
record: [ps, temp]
sensors: {temp_resolution: 0.05, temp_noise_sigma: 0.02}
faults:
  - {type: frozen, channel: p1, start_s: 20, duration_s: 10}
  - {type: saturated, channel: ps, start_s: 40, level: low}
  - {type: spikes, channel: temp, start_s: 0, rate_per_min: 6, magnitude: 15}
  - {type: dropout, channel: x, start_s: 50, duration_s: 2, mode: gap}
)",
                                    "drift.yaml");
  EXPECT_EQ(s.conditions.oil.name(), "ISO VG 68");
  ASSERT_TRUE(s.conditions.temperature);
  const TemperatureProfile& t = *s.conditions.temperature;
  EXPECT_EQ(t.kind, TemperatureProfile::Kind::warm_up_cooler);
  EXPECT_EQ(t.T0, 18.0);
  EXPECT_EQ(t.T_work, 52.0);
  EXPECT_EQ(t.tau_s, 300.0);
  EXPECT_EQ(t.start_s, 10.0);
  EXPECT_EQ(t.amplitude, 3.0);
  EXPECT_EQ(t.period_s, 400.0);
  EXPECT_EQ(t.cooler_start_s, 910.0);  // default: start_s + 3 tau_s
  ASSERT_EQ(s.conditions.supply.size(), 2u);
  EXPECT_EQ(s.conditions.supply[0].ramp_s, 2.0);
  EXPECT_EQ(s.conditions.supply[1].ps, 1.8e7);
  EXPECT_EQ(s.conditions.supply[1].ramp_s, 0.0);
  EXPECT_TRUE(s.record.ps);
  EXPECT_TRUE(s.record.temp);
  EXPECT_EQ(s.sensors.temp_resolution, 0.05);
  EXPECT_EQ(s.sensors.temp_noise_sigma, 0.02);
  ASSERT_EQ(s.faults.size(), 4u);
  EXPECT_EQ(s.faults[0].kind, SensorFault::Kind::frozen);
  EXPECT_EQ(s.faults[0].duration_s, 10.0);
  EXPECT_EQ(s.faults[1].channel, SensorChannel::ps);
  EXPECT_FALSE(s.faults[1].high);
  EXPECT_TRUE(std::isinf(s.faults[1].duration_s));
  EXPECT_EQ(s.faults[2].rate_per_min, 6.0);
  EXPECT_EQ(s.faults[2].magnitude, 15.0);
  EXPECT_TRUE(s.faults[3].gap);
  ASSERT_TRUE(s.effects.external_leakage);
  EXPECT_EQ(s.effects.external_leakage->onset_s, 30.0);
  EXPECT_EQ(s.effects.external_leakage->ramp_s, 2.0);
  // Drifting conditions keep the automatic step.
  EXPECT_EQ(integration_step(s), 2.5e-4);

  const Scenario custom = parse_scenario(
      "conditions:\n  oil: {nu40: 40, nu100: 6}\n  temperature: {profile: constant, T: 33}\n",
      "custom.yaml");
  EXPECT_EQ(custom.conditions.oil.nu40(), 40.0);
  EXPECT_EQ(custom.conditions.temperature->at(100.0), 33.0);
  EXPECT_FALSE(custom.record.temp);
}

TEST(ScenarioErrors, ConditionsAndFaultsNameFileLineColumn) {
  // A key the chosen profile does not take.
  std::string e =
      error_of("conditions:\n  temperature: {profile: cooler, T_work: 45, tau_s: 300}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("tau_s"), std::string::npos) << e;
  // Unknown profile.
  e = error_of("conditions:\n  temperature:\n    profile: sauna\n");
  EXPECT_NE(e.find("bad.yaml:3:14"), std::string::npos) << e;
  EXPECT_NE(e.find("warm_up_cooler"), std::string::npos) << e;
  // Temperature out of range.
  e = error_of("conditions:\n  temperature: {profile: constant, T: 400}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("T"), std::string::npos) << e;
  // Unknown oil grade.
  e = error_of("conditions:\n  oil: {grade: 50}\n");
  EXPECT_NE(e.find("bad.yaml:2:16"), std::string::npos) << e;
  EXPECT_NE(e.find("32, 46 or 68"), std::string::npos) << e;
  // Data-sheet viscosities the wrong way round.
  e = error_of("conditions:\n  oil: {nu40: 6, nu100: 40}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("nu100"), std::string::npos) << e;
  // Overlapping supply changes.
  e = error_of(
      "conditions:\n  supply:\n    - {t_s: 10, ps: 1.4e7, ramp_s: 5}\n    - {t_s: 12, ps: "
      "1.6e7}\n");
  EXPECT_NE(e.find("bad.yaml:4:"), std::string::npos) << e;
  EXPECT_NE(e.find("overlap"), std::string::npos) << e;
  // Supply out of range.
  e = error_of("conditions:\n  supply: [{t_s: 10, ps: -3}]\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("ps"), std::string::npos) << e;
  // A fault on a channel that is not recorded.
  e = error_of("faults:\n  - {type: frozen, channel: temp, start_s: 3}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("record"), std::string::npos) << e;
  // Unknown fault type, unknown channel, a key of another fault type.
  e = error_of("faults:\n  - {type: melted, channel: p1}\n");
  EXPECT_NE(e.find("bad.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("dropout"), std::string::npos) << e;
  e = error_of("faults:\n  - {type: frozen, channel: p3}\n");
  EXPECT_NE(e.find("p3"), std::string::npos) << e;
  e = error_of("faults:\n  - type: frozen\n    channel: p1\n    mode: gap\n");
  EXPECT_NE(e.find("bad.yaml:4:5"), std::string::npos) << e;
  EXPECT_NE(e.find("mode"), std::string::npos) << e;
  e = error_of("faults:\n  - {type: dropout, channel: p1, mode: nan}\n");
  EXPECT_NE(e.find("gap"), std::string::npos) << e;
  // Unknown optional column.
  e = error_of("record: [ps, flow]\n");
  EXPECT_NE(e.find("bad.yaml:1:14"), std::string::npos) << e;
  EXPECT_NE(e.find("flow"), std::string::npos) << e;
  // External leak onset out of range.
  e = error_of("effects:\n  external_leakage: {C_E: 1.0e-12, onset_s: -4}\n");
  EXPECT_NE(e.find("onset_s"), std::string::npos) << e;
}

TEST(ScenarioErrors, MissingFileIsAConfigError) {
  EXPECT_THROW(load_scenario("/nonexistent/scenario.yaml"), config::ConfigError);
}

TEST(Presets, FollowMODELsExperimentTable) {
  const auto names = preset_names();
  for (const char* required : {"paper-fig10", "paper-fig13", "paper-fig16"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), required), names.end()) << required;
  }
  const double per_lpm_mpa = 1.0 / 60000.0 / 1e6;
  const Scenario fig10 = preset("paper-fig10", 3);
  EXPECT_EQ(fig10.controller, ControllerKind::basic);
  EXPECT_EQ(fig10.duration_s, 30.0);
  EXPECT_EQ(fig10.seed, 3u);
  EXPECT_EQ(fig10.effects.internal_leakage->onset_s, 15.0);
  EXPECT_NEAR(fig10.effects.internal_leakage->C_L, 2.0e-12, 1e-18);
  const Scenario fig13 = preset("paper-fig13", 1);
  EXPECT_EQ(fig13.duration_s, 600.0);
  EXPECT_EQ(fig13.effects.internal_leakage->onset_s, 300.0);
  EXPECT_NEAR(fig13.effects.internal_leakage->C_L, 0.13 * per_lpm_mpa, 1e-20);
  const Scenario fig16 = preset("paper-fig16", 1);
  EXPECT_EQ(fig16.controller, ControllerKind::fault_tolerant);
  EXPECT_NEAR(fig16.effects.internal_leakage->C_L, 0.149 * per_lpm_mpa, 1e-20);
  EXPECT_FALSE(preset("healthy", 1).effects.internal_leakage);
  EXPECT_THROW(preset("paper-fig99", 1), std::invalid_argument);
}

TEST(Effects, EnableByNameUsesMODELsParameterNames) {
  Effects effects;
  const EffectParameter params[] = {{"offset", -2e5}, {"channel", std::string("p2")}};
  effects.enable("sensor_offset", params);
  ASSERT_TRUE(effects.sensor_offset);
  EXPECT_EQ(effects.sensor_offset->offset, -2e5);
  EXPECT_EQ(effects.sensor_offset->channel, PressureChannel::p2);
  const EffectParameter friction[] = {{"F_C", 120.0}};
  effects.enable("coulomb_friction", friction);
  const auto described = effects.describe();
  ASSERT_EQ(described.size(), 2u);
  EXPECT_EQ(described[0].name, "coulomb_friction");
  EXPECT_EQ(std::get<double>(described[0].params[0].value), 120.0);
  EXPECT_EQ(described[1].name, "sensor_offset");
  EXPECT_EQ(std::get<std::string>(described[1].params[1].value), "p2");
  const EffectParameter wrong[] = {{"Fc", 1.0}};
  EXPECT_THROW(effects.enable("coulomb_friction", wrong), EffectError);
  EXPECT_THROW(effects.enable("cavitation"), EffectError);
  EXPECT_EQ(Effects::names().size(), 11u);
  for (const auto name : Effects::names()) {
    Effects one;
    one.enable(name);
    ASSERT_EQ(one.describe().size(), 1u) << name;
    EXPECT_EQ(one.describe()[0].name, name);
    one.disable(name);
    EXPECT_TRUE(one.describe().empty()) << name;
  }
}

}  // namespace
}  // namespace leakmon::sim

namespace leakmon::sim {
namespace {

// Correlation of x with the reference after the first second, and the largest chamber pressure.
struct Tracking {
  double correlation = 0.0;
  double max_pressure = 0.0;
};
Tracking tracking_of(const capture::Capture& capture) {
  const auto& x = capture.column("x");
  const auto& r = capture.column("xref");
  const auto& p1 = capture.column("p1");
  const auto& p2 = capture.column("p2");
  double sx = 0, sr = 0, sxx = 0, srr = 0, sxr = 0, n = 0;
  Tracking out;
  for (std::size_t i = 500; i < x.size(); ++i) {
    sx += x[i];
    sr += r[i];
    sxx += x[i] * x[i];
    srr += r[i] * r[i];
    sxr += x[i] * r[i];
    n += 1.0;
    out.max_pressure = std::max({out.max_pressure, p1[i], p2[i]});
  }
  out.correlation = (sxr - sx * sr / n) / std::sqrt((sxx - sx * sx / n) * (srr - sr * sr / n));
  return out;
}

// The shipped other-rig examples run their rig with the paper's controller and track its steps,
// their transducers ranged for their supply (a 21 MPa supply would saturate MODEL.md's 20.7 MPa).
TEST(OtherRigScenarios, TheExamplesRunAndTrack) {
  for (const char* file : {"other-rig-50mm-21mpa.yaml", "other-rig-soft-heavy.yaml"}) {
    const Scenario s = load_scenario(test::source_dir() + "/sim/scenarios/" + file);
    EXPECT_FALSE(s.rig.nominal()) << file;
    EXPECT_TRUE(s.warnings.empty()) << file << ": " << s.warnings.front();
    EXPECT_GT(s.sensors.pressure_full_scale, 1.15 * s.params.ps) << file;
    const capture::Capture capture = simulate(s);
    const Tracking t = tracking_of(capture);
    EXPECT_GT(t.correlation, 0.95) << file;
    EXPECT_LT(t.max_pressure, s.sensors.pressure_full_scale) << file;
  }
  const Scenario high =
      load_scenario(test::source_dir() + "/sim/scenarios/other-rig-50mm-21mpa.yaml");
  EXPECT_EQ(high.sensors.pressure_full_scale, 25e6);
}

TEST(OtherRigScenarios, ThePressureRangeFollowsTheStatedSupplyUnlessSensorsSayOtherwise) {
  EXPECT_EQ(
      parse_scenario("rig: {supply_pressure: 28.0e6}\n", "a.yaml").sensors.pressure_full_scale,
      35e6);
  EXPECT_EQ(parse_scenario(
                "rig: {supply_pressure: 28.0e6}\nsensors: {pressure_full_scale: 4.0e7}\n", "b.yaml")
                .sensors.pressure_full_scale,
            40e6);
  // The paper's supply stated keeps the paper's transducers, and so its capture.
  const Scenario stated =
      parse_scenario("duration_s: 2\nrig: {supply_pressure: 17.2e6}\n", "c.yaml");
  EXPECT_EQ(stated.sensors.pressure_full_scale, SensorSettings{}.pressure_full_scale);
  Scenario paper = preset("healthy", 1);
  paper.duration_s = 2.0;
  EXPECT_EQ(simulate(stated).values, simulate(paper).values);
  // A rig that leaves the supply unsaid keeps them too.
  EXPECT_EQ(parse_scenario("rig: {bore: 0.05}\n", "d.yaml").sensors.pressure_full_scale, 20.7e6);
}

// MODEL.md "Other rigs": steps beyond the end stops, or a load needing more force than the rig
// can make, are errors at the reference's amplitude (or the rig); a load above half of it warns.
TEST(OtherRigScenarios, AReferenceTheRigCannotFollowIsAnErrorOrAWarning) {
  std::string e = error_of("rig: {stroke: 0.08}\n");
  EXPECT_NE(e.find("bad.yaml:1:6"), std::string::npos) << e;
  EXPECT_NE(e.find("end stops"), std::string::npos) << e;
  e = error_of("rig: {stroke: 0.5}\nreference: {amp_min: 0.1, amp_max: 0.3}\n");
  EXPECT_NE(e.find("bad.yaml:2:36"), std::string::npos) << e;
  // 500 kN/m x 50 mm = 25 kN against 6.3e-4 m^2 x 17.1 MPa = 10.8 kN.
  e = error_of("rig: {load_stiffness: 500.0e3}\n");
  EXPECT_NE(e.find("cannot follow"), std::string::npos) << e;
  EXPECT_NE(e.find("25 kN"), std::string::npos) << e;
  // 130 kN/m: 6.5 kN, 60 % of it.
  const Scenario warned = parse_scenario("rig: {load_stiffness: 130.0e3}\n", "warn.yaml");
  ASSERT_EQ(warned.warnings.size(), 1u);
  EXPECT_EQ(warned.warnings.front().rfind("warn.yaml:1:6: ", 0), 0u) << warned.warnings.front();
  EXPECT_NE(warned.warnings.front().find("60 %"), std::string::npos) << warned.warnings.front();
  // The paper's rig and its steps: nothing to say.
  EXPECT_TRUE(parse_scenario("name: paper\n", "paper.yaml").warnings.empty());
  for (const auto& entry :
       std::filesystem::directory_iterator(test::source_dir() + "/sim/scenarios")) {
    if (entry.path().extension() != ".yaml") continue;
    const Scenario s = load_scenario(entry.path().string());
    EXPECT_TRUE(s.warnings.empty()) << entry.path() << ": " << s.warnings.front();
  }
}

}  // namespace
}  // namespace leakmon::sim
