// `leakmon features` through the real binary (FORMATS.md): header t,rms, one row per window,
// t of the window's last sample, rms equal to the library's batch value, empty rms exactly where
// a window overlaps a gap, and clear errors for bad options and malformed captures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "capture/capture.hpp"
#include "dsp/streaming_features.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Outcome {
  int exit_code;
  std::string output;  // stdout and stderr
};

Outcome run_leakmon(const std::string& args, const std::string& dir) {
  const std::string log = dir + "/leakmon.log";
  const std::string command = test::leakmon_binary() + " " + args + " > " + log + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// A 500 Hz capture with p1 noisy around 8.65 MPa, gaps at the given rows.
std::vector<double> write_capture(const std::string& path, std::size_t rows,
                                  const std::vector<std::size_t>& gaps) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> noise(0.0, 2e4);
  capture::CaptureWriter writer(path, {"t", "x", "p1", "extra"}, {{"sample_rate_hz", "500"}});
  std::vector<double> p1(rows);
  for (std::size_t i = 0; i < rows; ++i) {
    p1[i] = 8.65e6 + 1e5 * std::sin(0.05 * static_cast<double>(i)) + noise(rng);
    for (std::size_t g : gaps) {
      if (g == i) p1[i] = capture::kGap;
    }
    const double row[] = {static_cast<double>(i) * 0.002, 0.01, p1[i], 1.0};
    writer.write_row(row);
  }
  writer.close();
  return p1;
}

// Runs `leakmon features` with the default parameters on a capture of `rows` rows with gaps and
// checks every output row against the batch transform.
void check_default_features(const std::string& name, std::size_t rows,
                            const std::vector<std::size_t>& gaps, std::size_t expected_empty) {
  const std::string dir = test::scratch_dir(name);
  const auto p1 = write_capture(dir + "/in.csv", rows, gaps);
  const Outcome run = run_leakmon(
      "features --in " + dir + "/in.csv --channel p1 --out " + dir + "/features.csv", dir);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find(dir + "/features.csv"), std::string::npos) << run.output;

  const auto lines = lines_of(dir + "/features.csv");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "t,rms");
  const std::size_t windows = (rows - 400) / 20 + 1;
  ASSERT_EQ(lines.size(), windows + 1);
  const auto expected = dsp::sliding_detail_features(p1, dsp::FeatureParams{});
  std::size_t empty = 0;
  for (std::size_t w = 0; w < windows; ++w) {
    const std::string& line = lines[w + 1];
    const auto comma = line.find(',');
    ASSERT_NE(comma, std::string::npos) << line;
    const double t = std::stod(line.substr(0, comma));
    EXPECT_EQ(t, static_cast<double>(w * 20 + 399) * 0.002) << line;
    bool holds_gap = false;
    for (std::size_t g : gaps) holds_gap |= (g >= w * 20 && g < w * 20 + 400);
    const std::string rms = line.substr(comma + 1);
    if (holds_gap) {
      EXPECT_EQ(rms, "") << "window " << w;
      ++empty;
    } else {
      ASSERT_FALSE(rms.empty()) << "window " << w;
      // The batch sums the squares in another order: equal to 1e-12.
      EXPECT_NEAR(std::stod(rms), expected[w].rms, 1e-12 * expected[w].rms) << "window " << w;
    }
  }
  EXPECT_EQ(empty, expected_empty);
}

TEST(FeaturesCli, WritesOneRowPerWindowWithEmptyRmsExactlyAtGaps) {
  // 450-451 lie in windows 3..22, 1333 in windows 47..66.
  check_default_features("features_cli_gaps", 2000, {450, 451, 1333}, 20u + 20u);
}

// The command reads the capture in chunks of 8192 rows: windows that straddle a chunk boundary,
// and gaps on either side of it, come out as in one piece.
TEST(FeaturesCli, LongCaptureReadInChunksGivesEveryWindow) {
  // 8191-8192 lie in windows 390..409, 16390 in windows 800..819.
  check_default_features("features_cli_chunks", 20000, {8191, 8192, 16390}, 20u + 20u);
}

TEST(FeaturesCli, OptionsChooseWaveletLevelWindowStepAndMode) {
  const std::string dir = test::scratch_dir("features_cli_options");
  const auto p1 = write_capture(dir + "/in.csv", 900, {});
  const Outcome run = run_leakmon("features --in " + dir + "/in.csv --channel p1 --out " + dir +
                                      "/f.csv --wavelet sym4 --level 3 --window 256 --step 30 "
                                      "--mode periodization",
                                  dir);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto lines = lines_of(dir + "/f.csv");
  const auto expected =
      dsp::sliding_detail_features(p1, {"sym4", 3, 256, 30, dsp::Mode::periodization});
  ASSERT_EQ(lines.size(), expected.size() + 1);
  for (std::size_t w = 0; w < expected.size(); ++w) {
    EXPECT_NEAR(std::stod(lines[w + 1].substr(lines[w + 1].find(',') + 1)), expected[w].rms,
                1e-12 * expected[w].rms);
  }
}

TEST(FeaturesCli, BadOptionsSayWhichAndWhy) {
  const std::string dir = test::scratch_dir("features_cli_bad_options");
  write_capture(dir + "/in.csv", 500, {});
  const std::string base = "features --in " + dir + "/in.csv --out " + dir + "/f.csv ";
  struct Bad {
    std::string args, expected;
  };
  const Bad cases[] = {
      {"--channel p1 --level 9", "--level: 9 is above the maximum level 4"},
      {"--channel p1 --window 8", "--window: 8 samples is shorter than the db8 filter"},
      {"--channel p1 --mode sym", "--mode: unknown extension mode 'sym'"},
      {"--channel p1 --wavelet morlet", "--wavelet: unknown wavelet 'morlet'"},
      {"--channel p1 --step 0", "option '--step': must be at least 1"},
      {"--channel p9", "no column 'p9' (columns: t, x, p1, extra)"},
      {"", "missing required option '--channel'"},
  };
  for (const Bad& bad : cases) {
    const Outcome run = run_leakmon(base + bad.args, dir);
    EXPECT_NE(run.exit_code, 0) << bad.args;
    EXPECT_NE(run.output.find(bad.expected), std::string::npos) << bad.args << "\n" << run.output;
  }
}

TEST(FeaturesCli, MalformedCaptureNamesFileLineAndColumn) {
  const std::string dir = test::scratch_dir("features_cli_malformed");
  std::ofstream(dir + "/bad.csv") << "# leakmon capture v1\nt,p1\n0,1\n0.002,oops\n";
  const Outcome run =
      run_leakmon("features --in " + dir + "/bad.csv --channel p1 --out " + dir + "/f.csv", dir);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find(dir + "/bad.csv:4:2: column 'p1': 'oops' is not a number"),
            std::string::npos)
      << run.output;
}

}  // namespace
}  // namespace leakmon
