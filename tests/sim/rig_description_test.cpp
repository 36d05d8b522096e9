// The rig's description (`rig:`, FORMATS.md): every key of MODEL.md "Other rigs" reaches the
// parameter it names, the valve from its data sheet gives MODEL.md's Kv, bad input fails at
// file:line:column naming the key, and a scenario runs the described rig.
#include "sim/rig_description.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "config/yaml_reader.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::sim {
namespace {

RigDescription parse(const std::string& yaml) {
  return read_rig(config::ConfigNode::load_string(yaml, "rig.yaml").at("rig"));
}

std::string error_of(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(RigDescription, EveryKeySetsItsParameter) {
  const RigDescription rig = parse(R"(rig:
  bore: 0.050
  rod: 0.028
  stroke: 0.50
  dead_volume: 2.0e-5
  line_volume: 1.0e-4
  supply_pressure: 21.0e6
  tank_pressure: 0.3e6
  bulk_modulus: 1.2e9
  moving_mass: 30
  viscous_friction: 800
  load_stiffness: 150.0e3
  valve_coefficient: 5.0e-7
  valve_time_constant: 0.004
  command_full_scale: 5
  null_leakage: 8.0e-13
  oil_grade: 32
)");
  const Parameters& p = rig.params;
  EXPECT_EQ(p.D, 0.050);
  EXPECT_EQ(p.d, 0.028);
  EXPECT_EQ(p.L, 0.50);
  EXPECT_EQ(p.V_dead, 2.0e-5);
  EXPECT_EQ(p.V_line, 1.0e-4);
  EXPECT_EQ(p.ps, 21.0e6);
  EXPECT_EQ(p.pt, 0.3e6);
  EXPECT_EQ(p.beta, 1.2e9);
  EXPECT_EQ(p.m, 30.0);
  EXPECT_EQ(p.b, 800.0);
  EXPECT_EQ(p.K_s, 150.0e3);
  EXPECT_EQ(p.Kv, 5.0e-7);
  EXPECT_EQ(p.tau, 0.004);
  EXPECT_EQ(p.u_max, 5.0);
  EXPECT_EQ(p.C_n, 8.0e-13);
  EXPECT_EQ(rig.oil.nu40(), 32.0);
  // What the description leaves out stays MODEL.md's nominal value.
  EXPECT_EQ(p.dp_lin, Parameters::nominal().dp_lin);
  EXPECT_EQ(p.sigma_w, Parameters::nominal().sigma_w);
  EXPECT_EQ(rig.stated.size(), 16u);
  EXPECT_EQ(rig.stated.front(), "bore");
  EXPECT_TRUE(rig.states_symbol("Kv"));
  EXPECT_TRUE(rig.states_symbol("oil"));
  EXPECT_TRUE(rig.states_symbol("K_s"));
  EXPECT_FALSE(rig.nominal());
  EXPECT_NE(rig.source.find("rig.yaml:2:"), std::string::npos) << rig.source;
}

TEST(RigDescription, EmptyOrMissingKeysAreThePapersRig) {
  const RigDescription rig = parse("rig: {}\n");
  EXPECT_TRUE(rig.nominal());
  EXPECT_EQ(rig.params.A(), Parameters::nominal().A());
  EXPECT_EQ(rig.oil.nu40(), Oil::standard().nu40());
  EXPECT_EQ(describe(rig), "the paper's rig (MODEL.md nominal)");
}

TEST(RigDescription, ValveFromItsDataSheet) {
  // MODEL.md: the Moog D765's 38 l/min rated at 70 bar total drop is Kv = 3.39e-7.
  const RigDescription rig = parse(R"(rig:
  valve_rated_flow: 6.3333e-4
  valve_rated_pressure_drop: 7.0e6
)");
  EXPECT_NEAR(rig.params.Kv, 3.39e-7, 0.005e-7);
  EXPECT_TRUE(rig.states_symbol("Kv"));
  EXPECT_NEAR(*rig_value(rig, "valve_rated_flow"), 6.3333e-4, 1e-9);
  // At another rated drop the same valve has another rated flow: Q = Kv sqrt(dp / 2).
  const RigDescription other = parse(R"(rig:
  valve_rated_flow: 1.0e-3
  valve_rated_pressure_drop: 3.5e6
)");
  EXPECT_NEAR(other.params.Kv, 1.0e-3 / std::sqrt(1.75e6), 1e-15);
  EXPECT_NE(describe(other).find("valve 60 l/min at 3.5 MPa"), std::string::npos)
      << describe(other);
}

TEST(RigDescription, OilFromItsDataSheet) {
  const RigDescription rig = parse("rig: {oil_viscosity_40: 100, oil_viscosity_100: 11.1}\n");
  EXPECT_EQ(rig.oil.nu40(), 100.0);
  EXPECT_EQ(rig.oil.nu100(), 11.1);
  EXPECT_FALSE(rig_value(rig, "oil_grade").has_value());
  EXPECT_EQ(*rig_value(parse("rig: {oil_grade: 68}\n"), "oil_grade"), 68.0);
}

TEST(RigDescription, BadInputNamesFileLineColumnAndKey) {
  EXPECT_NE(error_of("rig:\n  bore: 0.05\n  bor: 0.04\n").find("rig.yaml:3:"), std::string::npos);
  EXPECT_NE(error_of("rig:\n  bore: 0.05\n  bor: 0.04\n").find("unknown rig key 'bor'"),
            std::string::npos);
  EXPECT_NE(error_of("rig:\n  bore: 5\n").find("rig.yaml:2:"), std::string::npos);
  EXPECT_NE(error_of("rig:\n  bore: fifty\n").find("rig.yaml:2:"), std::string::npos);
  const std::string rod = error_of("rig:\n  bore: 0.03\n  rod: 0.03\n");
  EXPECT_NE(rod.find("rig.yaml:3:"), std::string::npos) << rod;
  EXPECT_NE(rod.find("thinner than the bore"), std::string::npos) << rod;
  // The paper's 25.4 mm rod does not fit a 25 mm bore that names no rod of its own.
  EXPECT_NE(error_of("rig:\n  bore: 0.025\n").find("thinner than the bore"), std::string::npos);
  const std::string half = error_of("rig:\n  valve_rated_flow: 1.0e-3\n");
  EXPECT_NE(half.find("valve_rated_pressure_drop"), std::string::npos) << half;
  EXPECT_NE(half.find("rig.yaml:2:"), std::string::npos) << half;
  const std::string twice = error_of(
      "rig:\n  valve_coefficient: 3.0e-7\n  valve_rated_flow: 1.0e-3\n"
      "  valve_rated_pressure_drop: 7.0e6\n");
  EXPECT_NE(twice.find("given twice"), std::string::npos) << twice;
  EXPECT_NE(error_of("rig: {oil_grade: 100}\n").find("32, 46 or 68"), std::string::npos);
  EXPECT_NE(error_of("rig: {oil_grade: 46, oil_viscosity_40: 46}\n").find("given twice"),
            std::string::npos);
  EXPECT_NE(error_of("rig: {oil_viscosity_40: 46}\n").find("give both"), std::string::npos);
  EXPECT_NE(error_of("rig: {supply_pressure: 1.0e6, tank_pressure: 2.0e6}\n").find("tank"),
            std::string::npos);
  EXPECT_NE(error_of("rig: [1, 2]\n").find("must be a mapping"), std::string::npos);
}

TEST(RigDescription, FileWithTopLevelRig) {
  const std::string dir = test::scratch_dir("rig_description_file");
  const std::string path = dir + "/rig.yaml";
  { std::ofstream(path) << "rig:\n  supply_pressure: 21.0e6\n  load_stiffness: 60.0e3\n"; }
  const RigDescription rig = load_rig_file(path);
  EXPECT_EQ(rig.params.ps, 21.0e6);
  EXPECT_EQ(rig.params.K_s, 60.0e3);
  EXPECT_EQ(describe(rig), "supply_pressure 21 MPa, load_stiffness 60 kN/m");
  { std::ofstream(path) << "rig:\n  bore: 0.05\ndetector: flow_balance\n"; }
  try {
    load_rig_file(path);
    ADD_FAILURE() << "a second top-level key was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":3:"), std::string::npos) << e.what();
  }
}

TEST(RigDescription, OneTableOfKeysCoversModelMd) {
  // MODEL.md "Other rigs" names these keys; the table must hold each once.
  for (const char* key : {"bore",
                          "rod",
                          "stroke",
                          "dead_volume",
                          "line_volume",
                          "supply_pressure",
                          "tank_pressure",
                          "bulk_modulus",
                          "moving_mass",
                          "viscous_friction",
                          "load_stiffness",
                          "valve_coefficient",
                          "valve_rated_flow",
                          "valve_rated_pressure_drop",
                          "valve_time_constant",
                          "command_full_scale",
                          "null_leakage",
                          "oil_grade",
                          "oil_viscosity_40",
                          "oil_viscosity_100"}) {
    int found = 0;
    for (const auto& k : rig_keys()) found += k.key == key ? 1 : 0;
    EXPECT_EQ(found, 1) << key;
  }
  EXPECT_EQ(rig_keys().size(), 20u);
}

TEST(ScenarioRig, AScenarioRunsItsRig) {
  Scenario s = parse_scenario(R"(name: other-rig
duration_s: 2
rig:
  bore: 0.050
  rod: 0.028
  supply_pressure: 21.0e6
  load_stiffness: 60.0e3
  oil_grade: 68
)",
                              "other.yaml");
  EXPECT_EQ(s.params.ps, 21.0e6);
  EXPECT_EQ(s.params.D, 0.050);
  EXPECT_EQ(s.conditions.oil.nu40(), 68.0);
  const capture::Capture capture = simulate(s);
  // At rest the chambers sit at (ps + pt) / 2 of the described supply, not the paper's.
  EXPECT_NEAR((capture.column("p1")[0] + capture.column("p2")[0]) / 2.0, (21.0e6 + 0.1e6) / 2.0,
              0.1e6);
  bool listed = false;
  for (const auto& [key, value] : capture.metadata) {
    if (key == "rig") listed = value.find("supply_pressure 21 MPa") != std::string::npos;
  }
  EXPECT_TRUE(listed);
}

TEST(ScenarioRig, PapersScenarioNamesNoRig) {
  const Scenario s = parse_scenario("name: paper\nduration_s: 1\n", "paper.yaml");
  EXPECT_TRUE(s.rig.nominal());
  for (const auto& [key, value] : simulate(s).metadata) EXPECT_NE(key, "rig");
}

TEST(ScenarioRig, AValueGivenTwiceIsAnError) {
  try {
    parse_scenario("rig: {supply_pressure: 21.0e6}\nparams: {ps: 20.0e6}\n", "twice.yaml");
    ADD_FAILURE() << "ps given in rig: and params: was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("twice.yaml:2:"), std::string::npos) << e.what();
  }
  try {
    parse_scenario("rig: {oil_grade: 32}\nconditions: {oil: {grade: 68}}\n", "oil.yaml");
    ADD_FAILURE() << "the oil given in rig: and conditions: was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("oil.yaml:2:"), std::string::npos) << e.what();
  }
  // A params: override of what the rig leaves unsaid is the simulated plant differing from it.
  const Scenario s =
      parse_scenario("rig: {supply_pressure: 21.0e6}\nparams: {beta: 9.0e8}\n", "override.yaml");
  EXPECT_EQ(s.params.beta, 9.0e8);
  EXPECT_EQ(s.rig.params.beta, Parameters::nominal().beta);
}

}  // namespace
}  // namespace leakmon::sim
