// The shipped Prometheus material against a running daemon: `leakmon run` on the simulated rig
// (a 0.15 l/min/MPa leak opening at 4 s, oil temperature acquired, state saved every second)
// is scraped over HTTP once it has raised its alarm; the scrape must show the new gauges with
// the rig's values, pass `promtool check metrics` (Debian's prometheus package), and name every
// metric the Grafana dashboard and the rules use (tests/prometheus/check_dashboard.py).
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "http/http_endpoint.hpp"
#include "tests/daemon/daemon_process.hpp"

namespace leakmon {
namespace {

using namespace std::chrono_literals;

void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// Exit status and output (stdout and stderr) of a shell command.
struct CommandResult {
  int status = -1;
  std::string output;
};
CommandResult run_command(const std::string& command) {
  CommandResult result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  while (const std::size_t n = std::fread(buffer, 1, sizeof(buffer), pipe)) {
    result.output.append(buffer, n);
  }
  const int status = ::pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// The value of the sample `series` (name and labels exactly as exposed), NaN when absent.
double sample_value(const std::string& text, const std::string& series) {
  const std::string key = "\n" + series + " ";
  const auto pos = ("\n" + text).find(key);
  if (pos == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + pos + key.size() - 1, nullptr);
}

std::string config_text(int port, int save_seconds = 1) {
  return "drivers:\n"
         "  - name: rig\n"
         "    type: sim\n"
         "    scenario: healthy\n"
         "    seed: 7\n"
         "    leak: {lpm_per_mpa: 0.15, onset_s: 22, ramp_s: 0.5}\n"
         "    channels: [xref, u, x, p1, p2, temp]\n"
         "sampling:\n"
         "  - {name: main, period_ms: 2, drivers: [rig]}\n"
         "actuators:\n"
         "  - name: cylinder\n"
         "    channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x, xref: rig.xref, "
         "temp: rig.temp}\n"
         "    detector: {kind: default, options: {settle_seconds: 1, learn_seconds: 20}}\n"
         "    alarm: {on_delay_s: 0.5, off_delay_s: 10, latching: false}\n"
         "events: {log: events.jsonl}\n"
         "metrics: {port: " +
         std::to_string(port) +
         "}\n"
         "state: {directory: state, save_seconds: " +
         std::to_string(save_seconds) + "}\n";
}

TEST(PrometheusLiveScrape, GaugesPromtoolLintAndDashboardNamesHold) {
  const std::string dir = test::scratch_dir("prometheus_live_scrape");
  const int port = test::free_port();
  write(dir + "/leakmon.yaml", config_text(port));
  test::DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml", "--duration", "70"},
                             dir + "/daemon.log");

  const std::string alarm =
      "leakmon_alarm_active{actuator=\"cylinder\",alarm=\"internal_leakage\","
      "alarm_state=\"active_unacknowledged\",state=\"active_unacknowledged\"}";
  std::string scrape;
  const bool alarmed = test::eventually(
      [&] {
        try {
          scrape = http::http_request("127.0.0.1", port, "GET", "/metrics").body;
        } catch (const std::exception&) {
          return false;
        }
        return sample_value(scrape, alarm) == 1.0 &&
               std::isfinite(sample_value(
                   scrape, "leakmon_learned_state_age_seconds{actuator=\"cylinder\"}"));
      },
      60s);
  ASSERT_TRUE(alarmed) << scrape << daemon.log();

  // The gauges with what the simulated rig has: the leak that opened, 40 degC oil, a state
  // saved within the last seconds, plausible sensors.
  const double leak = sample_value(scrape, "leakmon_leak_lpm_per_mpa{actuator=\"cylinder\"}");
  const double half_width =
      sample_value(scrape, "leakmon_leak_lpm_per_mpa_ci95{actuator=\"cylinder\"}");
  EXPECT_NEAR(leak, 0.15, 0.03) << scrape;
  EXPECT_GT(half_width, 0.0) << scrape;
  EXPECT_LT(half_width, 0.1) << scrape;
  EXPECT_NEAR(sample_value(scrape, "leakmon_oil_temperature_celsius{actuator=\"cylinder\"}"), 40.0,
              1.0)
      << scrape;
  const double age =
      sample_value(scrape, "leakmon_learned_state_age_seconds{actuator=\"cylinder\"}");
  EXPECT_GE(age, 0.0);
  EXPECT_LT(age, 10.0);
  EXPECT_EQ(
      sample_value(scrape,
                   "leakmon_sensor_status{actuator=\"cylinder\",channel=\"p1\",status=\"ok\"}"),
      1.0)
      << scrape;

  const std::string scrape_path = dir + "/scrape.txt";
  write(scrape_path, scrape);
  const std::string promtool = LEAKMON_PROMTOOL;
  const CommandResult lint = run_command(promtool + " check metrics < " + scrape_path);
  EXPECT_EQ(lint.status, 0) << lint.output;
  EXPECT_EQ(lint.output, "");
  // The same check fails on an exposition that breaks its rules, so passing means something.
  write(dir + "/bad.txt",
        "# HELP leakmon_things counted\n# TYPE leakmon_things counter\n"
        "leakmon_things 1\n");
  const CommandResult bad_lint = run_command(promtool + " check metrics < " + dir + "/bad.txt");
  EXPECT_NE(bad_lint.status, 0) << bad_lint.output;
  EXPECT_NE(bad_lint.output.find("_total"), std::string::npos) << bad_lint.output;

  const std::string source = test::source_dir();
  const std::string checker = test::python() + " " + source +
                              "/tests/prometheus/check_dashboard.py --promtool " + promtool + " ";
  const std::string rules = " " + source + "/prometheus/leakmon-alert-rules.yml " + source +
                            "/prometheus/leakmon-recording-rules.yml";
  const CommandResult dashboard = run_command(
      checker + source + "/prometheus/grafana/leakmon-dashboard.json " + scrape_path + rules);
  EXPECT_EQ(dashboard.status, 0) << dashboard.output;
  // A dashboard naming a metric the daemon does not emit is refused.
  std::string json =
      test::DaemonProcess::read_file(source + "/prometheus/grafana/leakmon-dashboard.json");
  const auto at = json.find("leakmon_oil_temperature_celsius");
  ASSERT_NE(at, std::string::npos);
  json.replace(at, std::string("leakmon_oil_temperature_celsius").size(), "leakmon_oil_temp_c");
  write(dir + "/misspelt.json", json);
  const CommandResult misspelt = run_command(checker + dir + "/misspelt.json " + scrape_path);
  EXPECT_NE(misspelt.status, 0) << misspelt.output;
  EXPECT_NE(misspelt.output.find("leakmon_oil_temp_c is not emitted"), std::string::npos)
      << misspelt.output;
  // So is one whose expression does not parse as PromQL (an unclosed parenthesis).
  json = test::DaemonProcess::read_file(source + "/prometheus/grafana/leakmon-dashboard.json");
  const std::string closed = "(leakmon_driver_up{instance=~\\\"$instance\\\"})";
  const auto paren = json.find(closed);
  ASSERT_NE(paren, std::string::npos);
  json.erase(paren + closed.size() - 1, 1);
  write(dir + "/unparsable.json", json);
  const CommandResult unparsable = run_command(checker + dir + "/unparsable.json " + scrape_path);
  EXPECT_NE(unparsable.status, 0) << unparsable.output;
  EXPECT_NE(unparsable.output.find("unclosed left parenthesis"), std::string::npos)
      << unparsable.output;

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(20s), 0) << daemon.log();
}

// The learned state's age across a restart: none before the first save of a fresh state, then
// after a restart the age of the file resumed from, which includes the time the daemon was down.
TEST(PrometheusLiveScrape, LearnedStateAgeCountsFromTheSavedFileAcrossARestart) {
  const std::string dir = test::scratch_dir("prometheus_state_age");
  const std::string age_series = "leakmon_learned_state_age_seconds{actuator=\"cylinder\"}";
  auto scrape_when_up = [](int port, std::string& scrape) {
    return test::eventually(
        [&] {
          try {
            scrape = http::http_request("127.0.0.1", port, "GET", "/metrics").body;
            return scrape.find("leakmon_detector_learning{") != std::string::npos;
          } catch (const std::exception&) {
            return false;
          }
        },
        15s);
  };
  std::string scrape;
  {
    const int port = test::free_port();
    write(dir + "/leakmon.yaml", config_text(port, 600));
    test::DaemonProcess first({"run", "--config", dir + "/leakmon.yaml"}, dir + "/first.log");
    ASSERT_TRUE(scrape_when_up(port, scrape)) << first.log();
    EXPECT_EQ(scrape.find(age_series), std::string::npos) << scrape;
    first.signal(SIGTERM);  // saves the learned state on the way out
    ASSERT_EQ(first.wait(20s), 0) << first.log();
  }
  const auto stopped = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(3s);
  const int port = test::free_port();
  write(dir + "/leakmon.yaml", config_text(port, 600));
  test::DaemonProcess second({"run", "--config", dir + "/leakmon.yaml"}, dir + "/second.log");
  ASSERT_TRUE(scrape_when_up(port, scrape)) << second.log();
  const double down_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped).count();
  const double age = sample_value(scrape, age_series);
  EXPECT_GE(age, 3.0) << scrape;
  EXPECT_LE(age, down_s + 1.0) << scrape;
  EXPECT_NE(second.log().find("resumed what was learned"), std::string::npos) << second.log();
  second.signal(SIGTERM);
  EXPECT_EQ(second.wait(20s), 0) << second.log();
}

}  // namespace
}  // namespace leakmon
