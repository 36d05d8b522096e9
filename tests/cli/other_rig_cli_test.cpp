// Other rigs through the binary (FORMATS.md "The rig's description"): `leakmon replay --rig`,
// its exclusion of --config, a bad rig file; check-config's warning for a value given both in an
// actuator's rig: and its detector's options; `leakmon evaluate --rigs other` on a few drawn rigs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/leakmon_cli.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

using test::run_leakmon;

std::string read(const std::string& path) { return test::read_text(path); }

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// The first internal_leakage raise's leak_coefficient in an events file; NaN without one.
double first_leak_size(const std::string& events) {
  std::istringstream in(read(events));
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("\"alarm_raised\"") == std::string::npos) continue;
    if (line.find("\"internal_leakage\"") == std::string::npos) continue;
    const std::string key = "\"leak_coefficient\": ";
    const auto at = line.find(key);
    if (at == std::string::npos) return NAN;
    return std::stod(line.substr(at + key.size()));
  }
  return NAN;
}

constexpr const char* kRig =
    "rig:\n"
    "  bore: 0.050\n"
    "  rod: 0.028\n"
    "  stroke: 0.50\n"
    "  supply_pressure: 21.0e6\n"
    "  load_stiffness: 150.0e3\n"
    "  moving_mass: 30\n"
    "  valve_rated_flow: 1.0e-3\n"
    "  valve_rated_pressure_drop: 7.0e6\n"
    "  line_volume: 1.0e-4\n";

TEST(ReplayRig, TheBuiltInDefaultsOnTheDescribedRig) {
  const std::string dir = test::scratch_dir("replay_rig_cli");
  ASSERT_EQ(
      run_leakmon("sim --scenario " + test::source_dir() +
                      "/sim/scenarios/other-rig-50mm-21mpa.yaml --out " + dir + "/capture.csv",
                  dir),
      0)
      << read(dir + "/leakmon.log");
  write(dir + "/rig.yaml", kRig);
  ASSERT_EQ(run_leakmon("replay --in " + dir + "/capture.csv --events " + dir +
                            "/told.jsonl --rig " + dir + "/rig.yaml",
                        dir),
            0)
      << read(dir + "/leakmon.log");
  ASSERT_EQ(
      run_leakmon("replay --in " + dir + "/capture.csv --events " + dir + "/defaults.jsonl", dir),
      0);
  // The scenario's leak is 2e-12; sized with the rig's piston, or with the paper's (its annulus
  // 6.33 cm^2 against this rig's 13.5 cm^2: 53 % low).
  EXPECT_NEAR(first_leak_size(dir + "/told.jsonl"), 2e-12, 0.2e-12);
  EXPECT_NEAR(first_leak_size(dir + "/defaults.jsonl"), 2e-12 * 6.334e-4 / 1.3477e-3, 0.1e-12);

  EXPECT_EQ(run_leakmon("replay --in " + dir + "/capture.csv --events " + dir + "/x.jsonl --rig " +
                            dir + "/rig.yaml --config " + dir + "/rig.yaml",
                        dir),
            2);
  EXPECT_NE(read(dir + "/leakmon.log").find("give --config or --rig, not both"), std::string::npos)
      << read(dir + "/leakmon.log");

  write(dir + "/bad.yaml", "rig:\n  bore: 0.05\n  supply: 21.0e6\n");
  EXPECT_EQ(run_leakmon("replay --in " + dir + "/capture.csv --events " + dir + "/x.jsonl --rig " +
                            dir + "/bad.yaml",
                        dir),
            1);
  const std::string log = read(dir + "/leakmon.log");
  EXPECT_NE(log.find("bad.yaml:3:11"), std::string::npos) << log;
  EXPECT_NE(log.find("unknown rig key 'supply'"), std::string::npos) << log;
}

TEST(CheckConfigRig, AValueGivenTwiceIsWarnedAboutNamingBothPlaces) {
  const std::string dir = test::scratch_dir("check_config_rig_cli");
  write(dir + "/rig.yaml",
        "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
        "metrics: {port: 0}\n"
        "state: {directory: state}\n"
        "actuators:\n"
        "  - name: cylinder\n"
        "    channels: {p1: p1, p2: p2, u: u, x: x}\n"
        "    rig: {bore: 0.05, supply_pressure: 21.0e6}\n"
        "    detector: {kind: default, options: {supply_pressure: 20.0e6}}\n");
  EXPECT_EQ(run_leakmon("check-config --no-probe " + dir + "/rig.yaml", dir), 0);
  const std::string log = read(dir + "/leakmon.log");
  EXPECT_NE(log.find("warning: " + dir + "/rig.yaml:8:58: "), std::string::npos) << log;
  EXPECT_NE(log.find("supply_pressure at " + dir + "/rig.yaml:7:40"), std::string::npos) << log;
  EXPECT_NE(log.find(": ok ("), std::string::npos) << log;
}

using Row = test::TsvRow;
using test::read_tsv;

const Row& row_of(const std::vector<Row>& rows, const std::string& channels, bool told) {
  for (const auto& r : rows) {
    if (r.at("channels") == channels && r.at("told") == (told ? "1" : "0")) return r;
  }
  throw std::runtime_error("no row " + channels);
}

// A few rigs drawn from MODEL.md "Other rigs" (fixed seed): every candidate has its row; told
// its rig the flow balance finds the valve-relative leaks and sizes them, not told it finds them
// with the paper's valve in its sizes; told, the pressure-only detectors call every rig whose
// mode is out of the band blind.
TEST(EvaluateRigs, ASmallOtherRigsEvaluation) {
  const std::string dir = test::scratch_dir("evaluate_rigs_cli");
  ASSERT_EQ(run_leakmon("evaluate --rigs other --out " + dir +
                            " --healthy-runs 1 --healthy-seconds 150 --runs-per-leak 4"
                            " --leaks 1e-12 --learn-seconds 40 --after-onset 60 --seed 8",
                        dir),
            0)
      << read(dir + "/leakmon.log");
  for (const char* file : {"rigs.md", "rigs.tsv", "rigs_runs.tsv"}) {
    EXPECT_GT(std::filesystem::file_size(dir + "/" + file), 100u) << file;
  }
  const std::vector<Row> rows = read_tsv(dir + "/rigs.tsv");
  ASSERT_EQ(rows.size(), 6u);
  const Row& told = row_of(rows, "p1,p2,u,x", true);
  const Row& untold = row_of(rows, "p1,p2,u,x", false);
  EXPECT_EQ(told.at("leak_runs"), "4");
  EXPECT_EQ(told.at("false_alarms"), "0");
  // Any misses are rigs whose spring holds less than 1 MPa at rest: a leak there has (almost) no
  // pressure difference to flow on at rest.
  EXPECT_GE(std::stoi(told.at("loaded_leak_runs")), 2);
  EXPECT_EQ(told.at("loaded_found"), told.at("loaded_leak_runs"));
  EXPECT_EQ(untold.at("loaded_found"), told.at("loaded_leak_runs"));
  // Seed 8's springless rig (run 1) learns by its motion and its 2.3e-13 leak is found in
  // motion, sized 12 % low; the others within 8 %.
  EXPECT_LT(std::stod(told.at("median_abs_size_error")), 0.15);
  EXPECT_GT(std::stod(untold.at("median_abs_size_error")), 0.2);
  EXPECT_GT(std::stod(told.at("healthy_hours")), 0.04);
  for (const char* channels : {"p1,p2", "p1"}) {
    const Row& pressure = row_of(rows, channels, true);
    EXPECT_EQ(pressure.at("out_of_band_blind"), pressure.at("out_of_band_runs")) << channels;
  }
  const std::string md = read(dir + "/rigs.md");
  EXPECT_NE(md.find("| p1,p2,u,x | told |"), std::string::npos) << md;
  EXPECT_NE(md.find("| p1,p2,u,x | not told |"), std::string::npos) << md;

  EXPECT_EQ(run_leakmon("evaluate --rigs moon --out " + dir, dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --rigs other --conditions restart --out " + dir, dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --rigs other --sensor-fault-runs 2 --out " + dir, dir), 2);
}

// Other rigs running test programs and seals that wear: rigs.md gets the tables per phase kind
// and per growth rate for every candidate, and rigs_programs.tsv / rigs_wear.tsv their rows.
TEST(EvaluateRigs, ProgramsAndWearOnOtherRigsHaveTheirTables) {
  const std::string dir = test::scratch_dir("evaluate_rigs_programs_cli");
  ASSERT_EQ(run_leakmon("evaluate --rigs other --conditions programs,wear --out " + dir +
                            " --healthy-runs 2 --runs-per-leak 2 --leaks 1e-12 --time-scale 0.1"
                            " --learn-seconds 40 --after-onset 60 --seed 9",
                        dir),
            0)
      << read(dir + "/leakmon.log");
  const std::string md = read(dir + "/rigs.md");
  EXPECT_NE(md.find("Test programs per phase kind"), std::string::npos) << md;
  EXPECT_NE(md.find("Seals that wear"), std::string::npos) << md;
  const std::vector<Row> phases = read_tsv(dir + "/rigs_programs.tsv");
  ASSERT_FALSE(phases.empty());
  double healthy_hours = 0.0;
  for (const Row& r : phases) {
    if (r.at("channels") == "p1,p2,u,x" && r.at("told") == "1") {
      healthy_hours += std::stod(r.at("healthy_hours"));
    }
  }
  EXPECT_GT(healthy_hours, 0.0);
  const std::vector<Row> wear = read_tsv(dir + "/rigs_wear.tsv");
  ASSERT_EQ(wear.size(), 6u * 4u);  // every candidate, all and the three growth rates
  EXPECT_EQ(wear.front().at("growth"), "all");
  EXPECT_EQ(wear.front().at("runs"), "1");
}

}  // namespace
}  // namespace leakmon
