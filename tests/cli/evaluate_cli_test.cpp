// `leakmon evaluate` end to end on a small fixed-seed Monte-Carlo (the full evaluation is the
// documented command in docs/detection.md): simulated rigs replayed through the daemon's
// pipeline, statistics asserted with margins.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "tests/support/leakmon_cli.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

using test::read_text;
using test::run_leakmon;

using Row = test::TsvRow;
using test::read_tsv;

const Row* find(const std::vector<Row>& rows, const std::string& detector, const std::string& leak,
                bool design, const std::string& threshold = "") {
  for (const auto& r : rows) {
    if (r.at("detector") != detector || r.at("controller") != "all" || r.at("leak") != leak) {
      continue;
    }
    if (design ? r.at("design") == "1" : r.at("threshold") == threshold) return &r;
  }
  return nullptr;
}

// One evaluation, all assertions (ctest runs each test in its own process).
TEST(EvaluateCommand, SmallFixedSeedEvaluation) {
  const std::string dir = test::scratch_dir("evaluate_cli");
  ASSERT_EQ(run_leakmon("evaluate --out " + dir +
                            " --healthy-runs 1 --healthy-seconds 150 --runs-per-leak 2"
                            " --leaks 1e-12 --learn-seconds 30 --after-onset 60 --seed 3"
                            " --keep-captures 1",
                        dir),
            0);
  for (const char* file : {"runs.json", "summary.json", "summary.tsv", "summary.md",
                           "size_coverage.tsv", "run-1.csv"}) {
    EXPECT_GT(std::filesystem::file_size(dir + "/" + file), 100u) << file;
  }
  const std::vector<Row> rows = read_tsv(dir + "/summary.tsv");

  // The default detector finds the target leak quickly, without false alarms.
  const Row* leak = find(rows, "default", "1e-12", true);
  ASSERT_NE(leak, nullptr);
  EXPECT_EQ(leak->at("leak_runs"), "2");
  EXPECT_EQ(leak->at("detected"), "2");
  EXPECT_LT(std::stod(leak->at("median_delay")), 30.0);
  // Healthy time: the healthy run plus the stretches before each onset.
  EXPECT_GT(std::stod(leak->at("healthy_hours")), 0.05);
  EXPECT_EQ(std::stod(leak->at("fa_per_hour")), 0.0);
  // The raising alarm carries the leak size; within a factor of two of the truth.
  EXPECT_LT(std::stod(leak->at("median_abs_size_error")), 0.5);

  // The flow balance's 95 % interval at its first raise: both runs raised; at least one of the
  // two intervals covers the true size (a 95 % interval misses both with probability 0.0025).
  const std::vector<Row> coverage = read_tsv(dir + "/size_coverage.tsv");
  const Row* all_runs = nullptr;
  for (const auto& row : coverage) {
    if (row.at("controller") == "all" && row.at("leak") == "1e-12") all_runs = &row;
  }
  ASSERT_NE(all_runs, nullptr);
  EXPECT_EQ(all_runs->at("raised"), "2");
  EXPECT_GE(std::stoi(all_runs->at("covered")), 1);
  EXPECT_LT(std::stod(all_runs->at("median_relative_half_width")), 0.5);

  // Lower thresholds never detect less (the ROC sweep is consistent).
  for (const char* detector : {"index_cusum", "flow_balance", "fused", "default"}) {
    double previous = 2.0;
    for (const char* threshold : {"0.25", "0.5", "1", "2", "3"}) {
      const Row* row = find(rows, detector, "1e-12", false, threshold);
      ASSERT_NE(row, nullptr) << detector << " " << threshold;
      const double rate = std::stod(row->at("detection_rate"));
      EXPECT_LE(rate, previous) << detector << " at " << threshold;
      previous = rate;
    }
  }
}

double sum_of(const std::vector<Row>& rows, const std::string& detector, const std::string& field,
              const std::string& key = "detector") {
  double sum = 0.0;
  for (const auto& r : rows) {
    if (r.at(key) == detector) sum += std::stod(r.at(field));
  }
  return sum;
}

// `--conditions programs,wear` on a short fixed-seed run (phases and wear times at a tenth of
// MODEL.md's): the per-phase table accounts for every healthy hour and false alarm of the
// programs, each phase kind gets its leak, and the wear table scores every seal that wears.
TEST(EvaluateCommand, ProgramsAndWearTables) {
  const std::string dir = test::scratch_dir("evaluate_cli_programs");
  ASSERT_EQ(run_leakmon("evaluate --out " + dir +
                            " --conditions programs,wear --healthy-runs 2 --healthy-seconds 150"
                            " --runs-per-leak 10 --leaks 2e-12 --learn-seconds 30"
                            " --time-scale 0.1 --seed 5",
                        dir),
            0);
  const std::vector<Row> programs = read_tsv(dir + "/programs.tsv");
  const std::vector<Row> wear = read_tsv(dir + "/wear.tsv");
  const std::vector<Row> conditions = read_tsv(dir + "/conditions.tsv");
  for (const char* detector : {"paper", "index_cusum_p1", "flow_balance", "default", "default_temp",
                               "detail_xcorr", "detail_xcorr_p1"}) {
    SCOPED_TRACE(detector);
    // Six rows: the five kinds and the holds that cannot be judged.
    std::vector<std::string> phases;
    for (const auto& r : programs) {
      if (r.at("detector") == detector) phases.push_back(r.at("phase"));
    }
    EXPECT_EQ(phases, (std::vector<std::string>{"steps", "hold", "hold (not judgeable)", "sine",
                                                "sweep", "triangle"}));
    // The phases split the programs' healthy time and false alarms as the condition's row counts
    // them (computed on another path: rates_of over the runs under `programs`).
    const Row* total = nullptr;
    for (const auto& r : conditions) {
      if (r.at("condition") == "programs" && r.at("detector") == detector) total = &r;
    }
    ASSERT_NE(total, nullptr);
    const double hours = std::stod(total->at("healthy_hours"));
    EXPECT_GT(hours, 0.05);
    EXPECT_NEAR(sum_of(programs, detector, "healthy_hours"), hours, 2e-3 * hours);
    EXPECT_EQ(sum_of(programs, detector, "false_alarms"), std::stod(total->at("false_alarms")));
    // Five program leak runs: one per kind (a hold's may count as not judgeable).
    std::map<std::string, double> leaks;
    for (const auto& r : programs) {
      if (r.at("detector") == detector) leaks[r.at("phase")] = std::stod(r.at("leak_runs"));
    }
    EXPECT_EQ(leaks["steps"], 1.0);
    EXPECT_EQ(leaks["hold"] + leaks["hold (not judgeable)"], 1.0);
    EXPECT_EQ(leaks["sine"], 1.0);
    EXPECT_EQ(leaks["sweep"], 1.0);
    EXPECT_EQ(leaks["triangle"], 1.0);
    for (const auto& r : programs) {
      if (r.at("detector") != detector) continue;
      EXPECT_LE(std::stod(r.at("found")) + std::stod(r.at("found_late")),
                std::stod(r.at("leak_runs")));
      EXPECT_LE(std::stod(r.at("fa_first_30s")), std::stod(r.at("false_alarms")));
    }
    // Five seals that wear, each in one growth band.
    std::map<std::string, const Row*> bands;
    for (const auto& r : wear) {
      if (r.at("detector") == detector) bands[r.at("growth")] = &r;
    }
    ASSERT_EQ(bands.size(), 4u);
    EXPECT_EQ(bands["all"]->at("runs"), "5");
    EXPECT_EQ(std::stoi(bands["slow"]->at("runs")) + std::stoi(bands["medium"]->at("runs")) +
                  std::stoi(bands["fast"]->at("runs")),
              5);
    const int found = std::stoi(bands["all"]->at("found"));
    EXPECT_LE(std::stoi(bands["all"]->at("found_before_target")), found);
    if (found > 0) {
      const double size = std::stod(bands["all"]->at("median_found_at"));
      EXPECT_GT(size, 0.0);
      EXPECT_LE(size, 5e-12);
    }
  }
  // With `temp` the default detector finds every seal that wears before it passes 1.5e-12
  // (issue 23: reported where it crossed the floor; keep it so).
  for (const auto& r : wear) {
    if (r.at("detector") == "default_temp" && r.at("growth") == "all") {
      EXPECT_EQ(r.at("found_before_target"), "5");
    }
  }
  const std::string text = read_text(dir + "/conditions.md");
  EXPECT_NE(text.find("Test programs per phase kind"), std::string::npos);
  EXPECT_NE(text.find("| default | hold (not judgeable) |"), std::string::npos);
  EXPECT_NE(text.find("Seals that wear"), std::string::npos);
  const std::string runs = read_text(dir + "/runs.json");
  EXPECT_NE(runs.find("\"program\": [{\"phase\": "), std::string::npos);
  EXPECT_NE(runs.find("\"wear_seconds\": "), std::string::npos);
}

TEST(EvaluateCommandOptions, RejectsBadOptions) {
  const std::string dir = test::scratch_dir("evaluate_cli_options");
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --jobs 0", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --leaks 1e-12,abc", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --keep-captures one", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --sensor-fault-runs -1", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --after-restart 0", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --conditions restart,nap", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate --out " + dir + " --conditions programs --time-scale 0", dir), 2);
  EXPECT_EQ(run_leakmon("evaluate", dir), 2);  // --out is required
}

}  // namespace
}  // namespace leakmon
