// The CAN drivers as the daemon sees them: `leakmon check-config` builds them through the
// driver registry from a whole daemon configuration, a mistake in a signal is reported at its
// file:line:column, and `leakmon run` replays a candump log through the acquisition loop into
// its raw recording with the values the log encodes.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Result {
  int status = -1;
  std::string output;
};

Result run(const std::string& command) {
  Result r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 512> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe) != nullptr) r.output += buffer.data();
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(CanDaemonConfig, CheckConfigBuildsTheCanlogDriverThroughTheRegistry) {
  // --no-probe: the example's default metrics port may be taken on a developer's machine.
  const Result ok = run(test::leakmon_binary() + " check-config --no-probe " + test::source_dir() +
                        "/io/canlog/replay_daemon.yaml");
  EXPECT_EQ(ok.status, 0) << ok.output;
}

TEST(CanDaemonConfig, SignalMistakesNameTheirLocation) {
  const std::string dir = test::scratch_dir("can_daemon_config");
  std::ifstream in(test::source_dir() + "/io/canlog/replay_daemon.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string from = "id: 0x102, start_bit: 7";
  const auto at = yaml.find(from);
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, from.size(), "id: 0x902, start_bit: 7");  // 0x902 needs 12 bits
  std::ofstream(dir + "/daemon.yaml") << yaml;
  std::filesystem::copy_file(test::source_dir() + "/io/canlog/sample.log", dir + "/sample.log");
  const Result bad = run(test::leakmon_binary() + " check-config " + dir + "/daemon.yaml");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find(dir + "/daemon.yaml:13:26"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("11 bits"), std::string::npos) << bad.output;
}

// p1 of every 0x101 frame in a candump log: little-endian bytes 0..1 at 500 Pa per bit,
// read here with plain string handling, independently of io/canlog.
std::vector<double> p1_in_log(const std::string& path) {
  std::vector<double> p1;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    const auto at = line.find(" 101#");
    if (at == std::string::npos) continue;
    const std::string hex = line.substr(at + 5, 4);
    const int low = std::stoi(hex.substr(0, 2), nullptr, 16);
    const int high = std::stoi(hex.substr(2, 2), nullptr, 16);
    p1.push_back((high * 256 + low) * 500.0);
  }
  return p1;
}

TEST(CanDaemonRun, ReplaysALogThroughTheAcquisitionLoopIntoTheRecording) {
  const std::string dir = test::scratch_dir("can_daemon_run");
  std::ifstream in(test::source_dir() + "/io/canlog/replay_daemon.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  yaml.replace(yaml.find("metrics:"), 8, "recording:\n  directory: rec\nmetrics:");
  // One log period per read whatever the wall clock does: on a loaded machine the loop may
  // miss cycles, which with `pace: log` would (correctly) skip log time.
  yaml.replace(yaml.find("pace: log"), 9, "pace: fast");
  std::ofstream(dir + "/daemon.yaml") << yaml;
  std::filesystem::copy_file(test::source_dir() + "/io/canlog/sample.log", dir + "/sample.log");
  const Result run_result =
      run("timeout 60 " + test::leakmon_binary() + " run --config " + dir + "/daemon.yaml");
  ASSERT_EQ(run_result.status, 0) << run_result.output;

  std::string csv;
  for (const auto& entry : std::filesystem::directory_iterator(dir + "/rec")) {
    if (entry.path().extension() == ".csv") csv = entry.path().string();
  }
  ASSERT_FALSE(csv.empty()) << "no recording in " << dir << "/rec";
  std::ifstream recording(csv);
  std::string line;
  while (std::getline(recording, line) && line.rfind('#', 0) == 0) {
  }
  ASSERT_EQ(line.substr(0, 6), "t,p1,p");
  std::vector<double> p1;
  while (std::getline(recording, line)) {
    const auto first = line.find(',');
    const auto second = line.find(',', first + 1);
    p1.push_back(std::stod(line.substr(first + 1, second - first - 1)));
  }
  // One tick per 2 ms frame period from the first frame: tick k carries frame k's p1, and one
  // more tick (still within max age) ends the stream.
  const std::vector<double> expected = p1_in_log(dir + "/sample.log");
  ASSERT_EQ(expected.size(), 50U);
  ASSERT_GE(p1.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) EXPECT_EQ(p1[k], expected[k]) << k;
}

}  // namespace
}  // namespace leakmon
