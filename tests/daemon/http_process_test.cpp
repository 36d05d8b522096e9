// The HTTP endpoint of a running `leakmon run` as a peer sees it: wrong methods, oversized
// requests and malformed targets get their 4xx answers, and POST /ack acknowledges nothing on a
// typo (the alarm stays unacknowledged) and exactly the named actuator otherwise.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "http/http_endpoint.hpp"
#include "tests/daemon/daemon_process.hpp"
#include "tests/http/raw_http.hpp"

namespace leakmon::daemon {
namespace {

using namespace std::chrono_literals;

// For requests http_request() cannot send (oversized, many headers, odd methods).
const auto status_line = test::raw_http_status_line;

std::string header_value(const http::HttpResponse& response, const std::string& name) {
  for (const auto& [key, value] : response.headers) {
    if (key == name) return value;
  }
  return "(none)";
}

// The alarm state of the only actuator, from the JSON status (the text between the quotes
// after "alarm_state":").
std::string alarm_state(int port) {
  const std::string body = http::http_request("127.0.0.1", port, "GET", "/status").body;
  const std::string_view key = "\"alarm_state\":\"";
  const auto at = body.find(key);
  if (at == std::string::npos) return "(no status)";
  const auto start = at + key.size();
  return body.substr(start, body.find('"', start) - start);
}

TEST(HttpProcess, LimitsMethodsAndStrictAcknowledgement) {
  const std::string dir = test::scratch_dir("http_process");
  const int port = test::free_port();
  // A simulated rig whose leak opens at 22 s, after 1 s settling and 20 s learning (the flow
  // balance learns from rests on both sides of zero load: a few seconds of steps hold too few);
  // the alarm latches so that it waits for an acknowledgement.
  std::ofstream(dir + "/leakmon.yaml")
      << "drivers:\n"
         "  - {name: rig, type: sim, scenario: healthy, seed: 7,\n"
         "     leak: {lpm_per_mpa: 0.5, onset_s: 22, ramp_s: 0.5}}\n"
         "sampling:\n"
         "  - {name: main, period_ms: 2, drivers: [rig], priority: 0}\n"
         "actuators:\n"
         "  - name: cylinder\n"
         "    channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x, xref: rig.xref}\n"
         "    detector: {kind: default, options: {settle_seconds: 1, learn_seconds: 20}}\n"
         "    alarm: {on_delay_s: 0.2, latching: true}\n"
         "events: {log: events.jsonl}\n"
         "metrics: {port: "
      << port
      << "}\n"
         "state: {directory: \"\"}\n"
         "realtime: {cpu_wakeup_latency_us: -1}\n";
  test::DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml"}, dir + "/daemon.log");
  ASSERT_TRUE(test::eventually(
      [&] {
        try {
          return http::http_request("127.0.0.1", port, "GET", "/metrics").status == 200;
        } catch (const std::exception&) {
          return false;
        }
      },
      20s))
      << daemon.log();

  // Methods: 405 with Allow on known paths, HEAD like GET without a body, 404 elsewhere.
  const http::HttpResponse post_metrics = http::http_request("127.0.0.1", port, "POST", "/metrics");
  EXPECT_EQ(post_metrics.status, 405);
  EXPECT_EQ(header_value(post_metrics, "allow"), "GET, HEAD");
  const http::HttpResponse get_ack = http::http_request("127.0.0.1", port, "GET", "/ack");
  EXPECT_EQ(get_ack.status, 405);
  EXPECT_EQ(header_value(get_ack, "allow"), "POST");
  const http::HttpResponse head = http::http_request("127.0.0.1", port, "HEAD", "/metrics");
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty());
  EXPECT_EQ(http::http_request("127.0.0.1", port, "GET", "/nothing").status, 404);
  const http::HttpResponse status = http::http_request("127.0.0.1", port, "GET", "/status");
  EXPECT_EQ(status.content_type, "application/json");
  EXPECT_EQ(status.body.find("nan"), std::string::npos) << status.body;
  EXPECT_EQ(status.body.find("NaN"), std::string::npos) << status.body;
  EXPECT_EQ(http::http_request("127.0.0.1", port, "GET", "/status?format=yaml").status, 400);

  // Sizes: request line (414), header count and size (431), body (413).
  EXPECT_NE(
      status_line(port, "GET /metrics?" + std::string(70000, 'a') + " HTTP/1.1\r\nHost: x\r\n\r\n")
          .find(" 414 "),
      std::string::npos);
  std::string many = "GET /metrics HTTP/1.1\r\nHost: x\r\n";
  for (int i = 0; i < 5000; ++i) many += "X-" + std::to_string(i) + ": y\r\n";
  EXPECT_NE(status_line(port, many + "\r\n").find(" 431 "), std::string::npos);
  std::string few = "GET /metrics HTTP/1.1\r\nHost: x\r\n";
  for (int i = 0; i < 150; ++i) few += "X-" + std::to_string(i) + ": y\r\n";
  EXPECT_NE(status_line(port, few + "\r\n").find(" 431 "), std::string::npos);
  EXPECT_NE(status_line(port, "POST /ack HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000\r\n\r\n")
                .find(" 413 "),
            std::string::npos);
  EXPECT_NE(status_line(port, "GET /metrics%zz HTTP/1.1\r\nHost: x\r\n\r\n").find(" 400 "),
            std::string::npos);

  // Wait for the latched leak alarm, then try every typo: each a 4xx, none acknowledges.
  ASSERT_TRUE(test::eventually([&] { return alarm_state(port) == "active_unacknowledged"; }, 60s))
      << alarm_state(port) << "\n"
      << daemon.log();
  const std::pair<const char*, int> typos[] = {{"/ack?foo=bar", 400},
                                               {"/ack?actuator", 400},
                                               {"/ack?actuator=", 400},
                                               {"/ack?%%%%", 400},
                                               {"/ack?actuator=cylindre", 404},
                                               {"/ack?actuator=cylinder&actuator=cylinder", 400},
                                               {"/ack?actuator=cylinder&x=1", 400}};
  for (const auto& [target, code] : typos) {
    EXPECT_EQ(http::http_request("127.0.0.1", port, "POST", target).status, code) << target;
  }
  EXPECT_EQ(alarm_state(port), "active_unacknowledged");
  const http::HttpResponse ack = http::http_request(
      "127.0.0.1", port, "POST", "/ack?actuator=" + http::percent_encode("cylinder"));
  EXPECT_EQ(ack.status, 200) << ack.body;
  EXPECT_EQ(alarm_state(port), "active_acknowledged");

  // `leakmon status` prints the human form from the JSON: states, never nan.
  test::DaemonProcess cli({"status", "--port", std::to_string(port)}, dir + "/cli.log");
  EXPECT_EQ(cli.wait(30s), 0) << cli.log();
  EXPECT_NE(cli.log().find("actuator cylinder: ALARM"), std::string::npos) << cli.log();
  EXPECT_NE(cli.log().find("alarm internal_leakage: active_acknowledged"), std::string::npos)
      << cli.log();
  EXPECT_EQ(cli.log().find("nan"), std::string::npos) << cli.log();

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(30s), 0) << daemon.log();
}

// Without options, `leakmon status` looks for /etc/leakmon/leakmon.yaml; when that does not exist
// it asks the built-in default address instead of failing on the missing file.
TEST(HttpProcess, StatusWithoutOptionsNeedsNoConfigurationFile) {
  if (std::filesystem::exists("/etc/leakmon/leakmon.yaml")) {
    GTEST_SKIP() << "/etc/leakmon/leakmon.yaml exists here: the default path is then used";
  }
  const std::string dir = test::scratch_dir("http_process_status");
  test::DaemonProcess status({"status"}, dir + "/status.log");
  status.wait(30s);
  EXPECT_EQ(status.log().find("leakmon.yaml"), std::string::npos) << status.log();
  // Either a daemon on the default port answered, or the message names that address.
  const bool answered = status.log().find("actuator ") != std::string::npos;
  EXPECT_TRUE(answered || status.log().find("127.0.0.1:9187") != std::string::npos) << status.log();
  test::DaemonProcess missing({"status", "--config", dir + "/absent.yaml"}, dir + "/missing.log");
  EXPECT_NE(missing.wait(30s), 0);
  EXPECT_NE(missing.log().find("absent.yaml"), std::string::npos) << missing.log();
}

}  // namespace
}  // namespace leakmon::daemon
