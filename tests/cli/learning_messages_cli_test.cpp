// Issue 25, "say what is happening": `leakmon replay` of a capture whose leak opened while the
// detector still learned printed "N samples, 0 events" and nothing else. `run` and `replay` now
// name each actuator's detector (and, for `default`, the signals that chose it), how long it
// learns, and when learning ended, or that it had not when the data ended.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <string>

#include "tests/daemon/daemon_process.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Invocation {
  int status = -1;
  std::string output;
};

Invocation run(const std::string& arguments) {
  Invocation result;
  FILE* pipe = ::popen((test::leakmon_binary() + " " + arguments + " 2>&1").c_str(), "r");
  std::array<char, 4096> buffer{};
  while (pipe != nullptr && std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) {
    result.output += buffer.data();
  }
  const int status = pipe != nullptr ? ::pclose(pipe) : -1;
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// The number after `prefix` in `text`, or NaN.
double number_after(const std::string& text, const std::string& prefix) {
  const auto at = text.find(prefix);
  return at == std::string::npos ? std::nan("") : std::stod(text.substr(at + prefix.size()));
}

TEST(LearningMessages, ReplaySaysWhichDetectorRanAndThatItWasStillLearning) {
  const std::string dir = test::scratch_dir("learning_messages_replay");
  // 30 s with a leak from 15 s: well inside the default detector's 90 s of learning.
  const Invocation sim = run("sim --preset paper-fig10 --out " + dir + "/fig10.csv");
  ASSERT_EQ(sim.status, 0) << sim.output;
  const Invocation replay =
      run("replay --in " + dir + "/fig10.csv --events " + dir + "/events.jsonl");
  ASSERT_EQ(replay.status, 0) << replay.output;
  EXPECT_NE(replay.output.find("actuator: detector flow_law (default for p1, p2, u, x); "
                               "learns the healthy rig during its first "),
            std::string::npos)
      << replay.output;
  const double learning = number_after(replay.output, "during its first ");
  EXPECT_GT(learning, 30.0) << replay.output;
  EXPECT_NE(replay.output.find("actuator: still learning at t = 30.0 s (learning takes"),
            std::string::npos)
      << replay.output;

  // With a short learning period the replay says when it ended.
  const std::string config = dir + "/short.yaml";
  std::ofstream(config) << "drivers: [{name: rig, type: sim}]\n"
                           "actuators:\n"
                           "  - name: cylinder\n"
                           "    channels: {p1: p1, p2: p2}\n"
                           "    detector: {kind: default, options: {settle_seconds: 1, "
                           "learn_seconds: 5}}\n"
                           "state: {directory: ''}\n"
                           "metrics: {port: 0}\n";
  const Invocation short_learning =
      run("replay --in " + dir + "/fig10.csv --events " + dir + "/short.jsonl --config " + config);
  ASSERT_EQ(short_learning.status, 0) << short_learning.output;
  EXPECT_NE(short_learning.output.find("cylinder: detector detail_xcorr (default for p1, p2)"),
            std::string::npos)
      << short_learning.output;
  const double ended =
      number_after(short_learning.output, "cylinder: learned the healthy rig until t = ");
  // The first window (0.8 s), settling (1 s) and learning (5 s), to the hop.
  EXPECT_GE(ended, 6.5) << short_learning.output;
  EXPECT_LE(ended, 7.5) << short_learning.output;
}

TEST(LearningMessages, RunLogsTheDetectorAndTheEndOfLearning) {
  const std::string dir = test::scratch_dir("learning_messages_run");
  const std::string config = dir + "/rig.yaml";
  std::ofstream(config) << "drivers: [{name: rig, type: sim, scenario: healthy, seed: 3}]\n"
                           "sampling: [{name: main, period_ms: 2, drivers: [rig], priority: 0}]\n"
                           "actuators:\n"
                           "  - name: cylinder\n"
                           "    channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x}\n"
                           "    detector: {kind: default, options: {settle_seconds: 1, "
                           "learn_seconds: 10}}\n"
                           "state: {directory: ''}\n"
                           "metrics: {port: 0}\n";
  // Real time: on a loaded machine missed cycles make gaps, which delay the end of learning.
  // The flow balance learns only once its blocks at rest cover three distinct loads (issue 23):
  // 10 s of the paper's steps (levels held 0.5-4 s) do; a shorter period might not, and then
  // starts over.
  const Invocation daemon = run("run --config " + config + " --duration 30");
  ASSERT_EQ(daemon.status, 0) << daemon.output;
  EXPECT_NE(daemon.output.find("cylinder: detector flow_law (default for p1, p2, u, x); "
                               "learns the healthy rig during its first 11.8 s of data"),
            std::string::npos)
      << daemon.output;
  // Not before the planned 11.8 s of data (to the hop); later when cycles were missed or the
  // first period lacked loads.
  const double ended = number_after(daemon.output, "cylinder: learned the healthy rig until t = ");
  EXPECT_GE(ended, 11.7) << daemon.output;
}

}  // namespace
}  // namespace leakmon
