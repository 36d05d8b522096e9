// Restarts of a real `leakmon run` process (replaying simulated captures of one rig): with a
// kept state the second start is not learning; a corrupt state file or a changed configuration
// gives one warning (log and event) and a fresh learning phase, never a crash.
#include <arpa/inet.h>
#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <cctype>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "capture/capture.hpp"
#include "http/http_endpoint.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/daemon/daemon_process.hpp"

namespace leakmon::daemon {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

// Learning takes settle 1 s + learn 20 s; the restarts replay 3 s captures, too short to learn.
std::string config_text(int port, int window) {
  return "drivers: [{name: bench, type: replay, path: capture.csv}]\n"
         "actuators:\n"
         "  - name: cyl\n"
         "    channels: {p1: p1, p2: p2, u: u, x: x, xref: xref}\n"
         "    features: {window: " +
         std::to_string(window) +
         "}\n"
         "    detector: {kind: default, options: {settle_seconds: 1, learn_seconds: 20}}\n"
         "events: {log: events.jsonl}\n"
         "state: {directory: state, save_seconds: 1}\n"
         "metrics: {port: " +
         std::to_string(port) + "}\n";
}

void write_capture(const std::string& dir, std::uint64_t seed, double seconds) {
  sim::Scenario scenario = sim::preset("healthy", seed);
  scenario.duration_s = seconds;
  scenario.effects.internal_leakage.reset();
  capture::write_capture(dir + "/capture.csv", sim::simulate(scenario));
}

struct DaemonRun {
  std::string log, events, learning_metric;
  std::string trend;  // the first /api/trend answer that held the actuator with a point
  int exit_code = -1;
};

// One daemon start on the current capture, until the capture ends. `learning_metric` is the
// first leakmon_detector_learning line the metrics endpoint served.
DaemonRun run_daemon(const std::string& dir, int port, const std::string& name) {
  fs::remove(dir + "/events.jsonl");
  test::DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml"}, dir + "/" + name + ".log");
  DaemonRun run;
  test::eventually(
      [&] {
        try {
          const auto body = http::http_request("127.0.0.1", port, "GET", "/metrics").body;
          const auto pos = body.find("leakmon_detector_learning{");
          if (pos == std::string::npos) return false;
          run.learning_metric = body.substr(pos, body.find('\n', pos) - pos);
          return true;
        } catch (const std::exception&) {
          return false;
        }
      },
      10s);
  test::eventually(
      [&] {
        try {
          run.trend = http::http_request("127.0.0.1", port, "GET", "/api/trend").body;
          // The actuator with at least one point: the page may be asked before the worker has
          // put the restored trend (or the first new point) in place.
          const std::string times = "\"time\":[";
          const auto first = run.trend.find(times);
          const auto point = first == std::string::npos ? first : first + times.size();
          return run.trend.find("\"name\":\"cyl\"") != std::string::npos &&
                 point < run.trend.size() &&
                 std::isdigit(static_cast<unsigned char>(run.trend[point]));
        } catch (const std::exception&) {
          return false;
        }
      },
      10s);
  run.exit_code = daemon.wait(60s);
  run.log = daemon.log();
  run.events = test::DaemonProcess::read_file(dir + "/events.jsonl");
  return run;
}

std::string show(const std::string& dir) {
  test::DaemonProcess cli({"state", "show", "--config", dir + "/leakmon.yaml"}, dir + "/show.log");
  EXPECT_EQ(cli.wait(20s), 0);
  return cli.log();
}

TEST(DaemonStateProcess, RestartKeepsLearningAndBadStateStartsFresh) {
  const std::string dir = test::scratch_dir("daemon_state_process");
  fs::remove_all(dir + "/state");
  const int port = test::free_port();
  std::ofstream(dir + "/leakmon.yaml") << config_text(port, 400);

  write_capture(dir, 31, 24.0);
  const DaemonRun first = run_daemon(dir, port, "first");
  ASSERT_EQ(first.exit_code, 0) << first.log;
  EXPECT_EQ(first.events.find("\"event\": \"state_"), std::string::npos) << "nothing saved before";
  const fs::path file = dir + "/state/cyl.state";
  ASSERT_TRUE(fs::exists(file)) << first.log;
  const std::string shown = show(dir);
  EXPECT_NE(shown.find("actuator cyl"), std::string::npos) << shown;
  EXPECT_NE(shown.find("(learned)"), std::string::npos) << shown;
  EXPECT_NE(shown.find("fits the configuration"), std::string::npos) << shown;
  const std::string saved = test::DaemonProcess::read_file(file.string());
  // The live page's trend is kept beside the state: its first point comes back after the
  // restart, before the points of the new run.
  const std::string trend_file = test::DaemonProcess::read_file(dir + "/state/cyl.trend.csv");
  ASSERT_EQ(trend_file.rfind("# leakmon trend 1\n", 0), 0u) << trend_file.substr(0, 200);
  const std::size_t first_row = trend_file.find('\n', trend_file.find('\n') + 1) + 1;
  const std::string first_time =
      trend_file.substr(first_row, trend_file.find(',', first_row) - first_row);
  EXPECT_GT(std::count(trend_file.begin(), trend_file.end(), '\n'), 10) << trend_file;

  // Restart: resumes, not learning from its first hop on (learning would need 21 s of 3).
  write_capture(dir, 32, 3.0);
  const DaemonRun second = run_daemon(dir, port, "second");
  ASSERT_EQ(second.exit_code, 0) << second.log;
  EXPECT_NE(second.events.find("\"state_restored\""), std::string::npos) << second.events;
  EXPECT_EQ(second.events.find("state_discarded"), std::string::npos) << second.events;
  EXPECT_NE(second.learning_metric.find("} 0"), std::string::npos) << second.learning_metric;
  EXPECT_EQ(second.events.find("alarm_raised"), std::string::npos) << second.events;
  EXPECT_NE(show(dir).find("(learned)"), std::string::npos);
  // Compared as numbers: the file keeps three decimals (620.220), JSON the shortest form (620.22).
  const std::string times = "\"time\":[";
  const auto restored = second.trend.find(times);
  ASSERT_NE(restored, std::string::npos) << second.trend.substr(0, 400);
  EXPECT_NEAR(std::stod(second.trend.substr(restored + times.size(), 32)), std::stod(first_time),
              5e-4)
      << first_time << " in " << second.trend.substr(restored, 200);

  // A corrupt (truncated) file: one warning, then a fresh learning phase.
  std::ofstream(file, std::ios::trunc) << saved.substr(0, saved.size() / 2);
  const DaemonRun corrupt = run_daemon(dir, port, "corrupt");
  ASSERT_EQ(corrupt.exit_code, 0) << corrupt.log;
  EXPECT_NE(corrupt.events.find("\"state_discarded\""), std::string::npos) << corrupt.events;
  EXPECT_NE(corrupt.events.find("truncated"), std::string::npos) << corrupt.events;
  EXPECT_NE(corrupt.log.find("warning: state_discarded"), std::string::npos) << corrupt.log;
  EXPECT_NE(corrupt.learning_metric.find("} 1"), std::string::npos) << corrupt.learning_metric;
  EXPECT_NE(show(dir).find("(still learning)"), std::string::npos);

  // A changed configuration (another window): one warning naming the change, fresh learning.
  std::ofstream(file, std::ios::trunc) << saved;
  std::ofstream(dir + "/leakmon.yaml", std::ios::trunc) << config_text(port, 512);
  EXPECT_NE(show(dir).find("does NOT fit"), std::string::npos);
  const DaemonRun changed = run_daemon(dir, port, "changed");
  ASSERT_EQ(changed.exit_code, 0) << changed.log;
  EXPECT_NE(changed.events.find("configuration changed"), std::string::npos) << changed.events;
  EXPECT_NE(changed.events.find("window=512"), std::string::npos) << changed.events;
  EXPECT_NE(changed.learning_metric.find("} 1"), std::string::npos) << changed.learning_metric;

  // Reset deletes it.
  test::DaemonProcess reset({"state", "reset", "--config", dir + "/leakmon.yaml"},
                            dir + "/reset.log");
  EXPECT_EQ(reset.wait(20s), 0) << reset.log();
  EXPECT_FALSE(fs::exists(file));
}

// A rig that may already leak at installation: learn from a known-good capture instead.
TEST(DaemonStateProcess, LearnFromAKnownGoodCapture) {
  const std::string dir = test::scratch_dir("daemon_state_learn");
  fs::remove_all(dir + "/state");
  std::ofstream(dir + "/leakmon.yaml") << config_text(test::free_port(), 400);
  write_capture(dir, 41, 24.0);
  test::DaemonProcess learn(
      {"learn", "--config", dir + "/leakmon.yaml", "--in", dir + "/capture.csv"},
      dir + "/learn.log");
  ASSERT_EQ(learn.wait(60s), 0) << learn.log();
  EXPECT_NE(learn.log().find("actuator cyl: learned"), std::string::npos) << learn.log();
  EXPECT_NE(show(dir).find("(learned)"), std::string::npos);
  EXPECT_NE(show(dir).find("fits the configuration"), std::string::npos);

  // Too short to learn: said so, exit status 1.
  write_capture(dir, 42, 5.0);
  test::DaemonProcess short_learn({"state", "learn", "--config", dir + "/leakmon.yaml", "--in",
                                   dir + "/capture.csv", "--state-dir", dir + "/short"},
                                  dir + "/short.log");
  EXPECT_EQ(short_learn.wait(60s), 1) << short_learn.log();
  EXPECT_NE(short_learn.log().find("still learning"), std::string::npos) << short_learn.log();

  test::DaemonProcess help({"state", "--help"}, dir + "/help.log");
  EXPECT_EQ(help.wait(20s), 0);
  EXPECT_NE(help.log().find("reset"), std::string::npos) << help.log();
}

}  // namespace
}  // namespace leakmon::daemon
