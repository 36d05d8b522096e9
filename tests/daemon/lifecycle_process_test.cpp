// `leakmon run` as systemd runs it: the pre-flight refuses what check-config refuses (with
// file:line:column), the event log opens with daemon_started and closes with daemon_stopped
// (the reason and the uptime), and a rejected reload whose file carries invalid UTF-8 and escape
// sequences leaves the event log valid UTF-8 JSON and the log free of raw escapes.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "tests/daemon/daemon_process.hpp"

namespace leakmon::daemon {
namespace {

using namespace std::chrono_literals;

std::string config_text(int port, const std::string& extra = "") {
  return "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
         "sampling: [{name: main, period_ms: 2, drivers: [rig], priority: 0}]\n"
         "actuators: [{name: cyl, channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x}}]\n"
         "events: {log: events.jsonl}\n"
         "state: {directory: ''}\n"
         "worker: {priority: 0}\n"
         "realtime: {cpu_wakeup_latency_us: -1}\n"
         "metrics: {port: " +
         std::to_string(port) + "}\n" + extra;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

bool valid_utf8_without_controls(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    unsigned code = 0;
    const std::size_t length = config::utf8_sequence(text, i, code);
    if (length == 0 || (code < 0x20 && code != '\n') || (code >= 0x7f && code < 0xa0)) {
      return false;
    }
    i += length;
  }
  return true;
}

TEST(LifecycleProcess, StartedAndStoppedFrameTheEventsAndBadTextIsEscaped) {
  const std::string dir = test::scratch_dir("lifecycle_process");
  const std::string config = dir + "/leakmon.yaml";
  std::ofstream(config) << config_text(test::free_port());
  test::DaemonProcess daemon({"run", "--config", config, "--duration", "4"}, dir + "/out.log");
  const std::string events = dir + "/events.jsonl";
  ASSERT_TRUE(test::eventually(
      [&] {
        return test::DaemonProcess::read_file(events).find("daemon_started") != std::string::npos;
      },
      20s))
      << daemon.log();
  // A reload the daemon must reject: an unknown key of invalid UTF-8 and an escape sequence.
  std::ofstream(config) << config_text(test::free_port(), "\"\\e[2Jbad\xff\xfekey\": 1\n");
  daemon.signal(SIGHUP);
  ASSERT_EQ(daemon.wait(30s), 0) << daemon.log();

  const auto lines = lines_of(test::DaemonProcess::read_file(events));
  ASSERT_GE(lines.size(), 3u);
  EXPECT_NE(lines.front().find("\"event\": \"daemon_started\""), std::string::npos)
      << lines.front();
  EXPECT_NE(lines.front().find("\"pid\": " + std::to_string(daemon.pid())), std::string::npos)
      << lines.front();
  EXPECT_NE(lines.front().find("\"config\": \"" + config + "\""), std::string::npos);
  EXPECT_NE(lines.front().find("\"version\": \""), std::string::npos);
  EXPECT_NE(lines.back().find("\"event\": \"daemon_stopped\""), std::string::npos) << lines.back();
  EXPECT_NE(lines.back().find("\"reason\": \"duration\""), std::string::npos) << lines.back();
  EXPECT_NE(lines.back().find("\"uptime_s\": 4."), std::string::npos) << lines.back();
  bool rejected = false;
  for (const auto& line : lines) {
    EXPECT_TRUE(valid_utf8_without_controls(line)) << line;
    if (line.find("config_rejected") == std::string::npos) continue;
    rejected = true;
    EXPECT_NE(line.find("unknown key '\\\\x1b[2Jbad\xef\xbf\xbd\xef\xbf\xbdkey'"),
              std::string::npos)
        << line;
  }
  EXPECT_TRUE(rejected);
  EXPECT_TRUE(valid_utf8_without_controls(daemon.log())) << daemon.log();
}

TEST(LifecycleProcess, SigtermIsTheStopReason) {
  const std::string dir = test::scratch_dir("lifecycle_process_sigterm");
  const std::string config = dir + "/leakmon.yaml";
  std::ofstream(config) << config_text(test::free_port());
  test::DaemonProcess daemon({"run", "--config", config}, dir + "/out.log");
  const std::string events = dir + "/events.jsonl";
  ASSERT_TRUE(test::eventually(
      [&] {
        return test::DaemonProcess::read_file(events).find("daemon_started") != std::string::npos;
      },
      20s));
  daemon.signal(SIGTERM);
  ASSERT_EQ(daemon.wait(30s), 0) << daemon.log();
  const auto lines = lines_of(test::DaemonProcess::read_file(events));
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.back().find("\"reason\": \"signal SIGTERM\""), std::string::npos) << lines.back();
}

// ExecStartPre=check-config and the start agree: what one refuses, the other refuses with the
// same file:line:column message, before anything is acquired.
TEST(LifecycleProcess, RunRefusesWhatCheckConfigRefuses) {
  const std::string dir = test::scratch_dir("lifecycle_process_preflight");
  const std::string config = dir + "/leakmon.yaml";
  std::ofstream(config) << "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
                           "actuators: [{name: cyl, channels: {p1: rig.p1}}]\n"
                           "state: {directory: ''}\n"
                           "events: {log: "
                        << dir << "}\n";
  const std::string expected = config + ":4:15: events.log: event log '" + dir + "' is a directory";
  test::DaemonProcess check({"check-config", config}, dir + "/check.log");
  EXPECT_EQ(check.wait(30s), 1);
  EXPECT_NE(check.log().find(expected), std::string::npos) << check.log();
  test::DaemonProcess run({"run", "--config", config}, dir + "/run.log");
  EXPECT_EQ(run.wait(30s), 1);
  EXPECT_NE(run.log().find(expected), std::string::npos) << run.log();
}

}  // namespace
}  // namespace leakmon::daemon
