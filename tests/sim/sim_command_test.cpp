// `leakmon sim` as FORMATS.md specifies it, run as the real binary.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "capture/capture.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Result {
  int exit_code;
  std::string output;
};

Result run(const std::string& args) {
  const std::string command = test::leakmon_binary() + " sim " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[512];
  while (pipe && std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  const int status = pipe ? pclose(pipe) : -1;
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST(SimCommand, PresetWritesTheCaptureWithMetadata) {
  const std::string dir = test::scratch_dir("sim_command_preset");
  const Result r = run("--preset paper-fig10 --seed 7 --duration 2 --out " + dir + "/fig10.csv");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const capture::Capture capture = capture::read_capture(dir + "/fig10.csv");
  for (const char* column : {"t", "xref", "u", "x", "p1", "p2", "q_int"}) {
    EXPECT_TRUE(capture.has(column)) << column;
  }
  EXPECT_EQ(capture.rows(), 1000u);
  EXPECT_EQ(capture.metadata_value("source"), "sim preset paper-fig10 seed 7");
  EXPECT_EQ(capture.metadata_value("seed"), "7");
  EXPECT_EQ(capture.metadata_value("effect"), "internal_leakage C_L=2e-12 onset_s=15 ramp_s=0");
  EXPECT_EQ(capture.sample_rate_hz(), 500.0);
}

// Issue 25: `sim --preset paper-fig13 --duration 120` ended silently before the preset's leak
// at 300 s. The run now says what the capture holds, and warns of what starts after its end.
TEST(SimCommand, SaysWhatTheRunHoldsAndWarnsOfALeakAfterItsEnd) {
  const std::string dir = test::scratch_dir("sim_command_summary");
  const Result short_run = run("--preset paper-fig13 --duration 2 --out " + dir + "/short.csv");
  ASSERT_EQ(short_run.exit_code, 0) << short_run.output;
  for (const char* part :
       {"preset paper-fig13, seed 1, basic controller: 2 s at 500 Hz (1000 rows)",
        "internal leak 0.13 l/min/MPa from t = 300 s", "short.csv"}) {
    EXPECT_NE(short_run.output.find(part), std::string::npos) << part << "\n" << short_run.output;
  }
  EXPECT_NE(short_run.output.find("warning: internal_leakage starts at t = 300 s, after the run "
                                  "ends at t = 2 s: the capture holds no leak"),
            std::string::npos)
      << short_run.output;

  // A run that reaches its leak is summarised without a warning.
  const Result full = run("--preset paper-fig10 --duration 16 --out " + dir + "/full.csv");
  ASSERT_EQ(full.exit_code, 0) << full.output;
  EXPECT_NE(full.output.find("internal leak 0.12 l/min/MPa from t = 15 s"), std::string::npos)
      << full.output;
  EXPECT_EQ(full.output.find("warning"), std::string::npos) << full.output;

  const Result healthy = run("--preset healthy --duration 1 --out " + dir + "/healthy.csv");
  ASSERT_EQ(healthy.exit_code, 0) << healthy.output;
  EXPECT_NE(healthy.output.find("no effects (healthy)"), std::string::npos) << healthy.output;
}

TEST(SimCommand, ScenarioFileRunsAndBadFilesFailWithTheirLocation) {
  const std::string dir = test::scratch_dir("sim_command_scenario");
  const Result ok =
      run("--scenario " + test::source_dir() +
          "/sim/scenarios/supply-disturbances.yaml --duration 1 --out " + dir + "/s.csv");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const capture::Capture capture = capture::read_capture(dir + "/s.csv");
  EXPECT_EQ(capture.rows(), 500u);
  int effects = 0;
  for (const auto& [key, value] : capture.metadata) effects += key == "effect";
  EXPECT_EQ(effects, 3);

  const std::string bad = dir + "/bad.yaml";
  std::ofstream(bad) << "name: bad\neffects:\n  supply_ripple: {dP: 5.0e5, f: -3}\n";
  const Result failed = run("--scenario " + bad + " --out " + dir + "/never.csv");
  EXPECT_EQ(failed.exit_code, 1);
  EXPECT_NE(failed.output.find(bad + ":3:"), std::string::npos) << failed.output;
  EXPECT_NE(failed.output.find("f"), std::string::npos) << failed.output;
}

TEST(SimCommand, DriftingConditionsAndFaultsReachTheCapture) {
  const std::string dir = test::scratch_dir("sim_command_drift");
  const Result ok = run("--scenario " + test::source_dir() +
                        "/sim/scenarios/sensor-faults.yaml --duration 100 --out " + dir + "/f.csv");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const capture::Capture capture = capture::read_capture(dir + "/f.csv");
  ASSERT_TRUE(capture.has("temp"));
  ASSERT_TRUE(capture.has("ps"));
  EXPECT_EQ(capture.metadata_value("temperature"), "constant T=45");
  int faults = 0;
  for (const auto& [key, value] : capture.metadata) faults += key == "sensor_fault";
  EXPECT_EQ(faults, 6);
  // p1 frozen from 40 s to 60 s: one value repeated exactly; p2 at full scale from 90 s.
  const auto& p1 = capture.column("p1");
  for (std::size_t k = 20000; k < 30000; ++k) ASSERT_EQ(p1[k], p1[19999]) << k;
  EXPECT_EQ(capture.column("p2")[46000], 20.7e6);
  EXPECT_NEAR(capture.column("temp")[100], 45.0, 0.3);

  // --record adds the optional columns to a preset.
  const Result recorded =
      run("--preset healthy --duration 1 --record temp,ps --out " + dir + "/r.csv");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.output;
  const capture::Capture r = capture::read_capture(dir + "/r.csv");
  EXPECT_EQ(r.columns,
            (std::vector<std::string>{"t", "xref", "u", "x", "p1", "p2", "q_int", "ps", "temp"}));
  EXPECT_NEAR(r.column("temp")[0], 40.0, 0.3);
  EXPECT_NEAR(r.column("ps")[0], 17.2e6, 3e4);
  EXPECT_EQ(run("--preset healthy --record flow --out /tmp/x.csv").exit_code, 2);
}

TEST(SimCommand, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run("--preset nope --out /tmp/x.csv").exit_code, 2);
  EXPECT_EQ(run("--out /tmp/x.csv").exit_code, 2);
  const Result both = run("--preset healthy --scenario a.yaml --out /tmp/x.csv");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_NE(both.output.find("exactly one"), std::string::npos) << both.output;
  const Result help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("paper-fig13"), std::string::npos) << help.output;
}

}  // namespace
}  // namespace leakmon
