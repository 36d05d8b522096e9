// Scenario files and presets: the examples in sim/scenarios/ load and run; bad input fails
// with file:line:column and the field's path; presets carry MODEL.md's experiment table.
#include <gtest/gtest.h>

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
