// `leakmon run` with an `mqtt` output against Debian's mosquitto broker, started by the test on
// a free local port: every event delivered in order on its topic, the retained status with its
// birth message and last will, the broker killed and restarted mid-run with nothing lost, an
// absent or silent broker that never stalls the daemon, and refused credentials as a clear
// error. The subscriber is Debian's mosquitto_sub.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/daemon/daemon_process.hpp"
#include "tests/io/mqtt/mosquitto_peers.hpp"

namespace leakmon::test {
namespace {

using namespace std::chrono_literals;

const std::string kTopic = "leakmon/lab/rig1";

std::string http_get(int port, const std::string& path) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::string response;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
    const std::string request = "GET " + path + " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
    if (::write(fd, request.data(), request.size()) == static_cast<ssize_t>(request.size())) {
      char buffer[8192];
      for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;)
        response.append(buffer, static_cast<std::size_t>(n));
    }
  }
  ::close(fd);
  return response;
}

// The value of the first /metrics sample whose line starts with `series` followed by a space
// (e.g. `leakmon_mqtt_connected{output="fleet"}`); NaN when absent.
double metric(int port, const std::string& series) {
  std::istringstream in(http_get(port, "/metrics"));
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(series + " ", 0) == 0) return std::stod(line.substr(series.size() + 1));
  }
  return std::nan("");
}

std::string daemon_config(int metrics_port, double period_ms, const std::string& outputs) {
  return "drivers:\n"
         "  - {name: rig, type: sim, scenario: healthy, seed: 7}\n"
         "sampling:\n"
         "  - {name: main, period_ms: " +
         std::to_string(period_ms) +
         ", drivers: [rig]}\n"
         "actuators:\n"
         "  - name: cylinder\n"
         "    channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x, xref: rig.xref}\n"
         "    detector: {kind: default, options: {settle_seconds: 1, learn_seconds: 5}}\n"
         "events: {log: events.jsonl}\n"
         "metrics: {port: " +
         std::to_string(metrics_port) +
         "}\n"
         "state: {directory: state}\n"
         "outputs:\n" +
         outputs;
}

std::string mqtt_output(const std::string& name, int port, const std::string& extra = "") {
  return "  - {name: " + name + ", type: mqtt, host: 127.0.0.1, port: " + std::to_string(port) +
         ", topic: " + kTopic + ", features_hz: 4, connect_timeout_s: 1, reconnect_max_s: 1" +
         ", queue: {directory: queue-" + name + "}" + extra + "}\n";
}

// The event log's lines and the event messages received must be the same objects in the same
// order; a message may arrive twice (QoS 1 is at least once: a PUBACK lost with the broker, or
// the restarted broker sending its saved copy to the subscriber again), so repetitions (events
// carry their time to the millisecond) are set aside and counted.
std::vector<std::string> without_repeats(const std::vector<std::string>& in, int* repeats) {
  std::vector<std::string> out;
  for (const auto& s : in) {
    if (std::find(out.begin(), out.end(), s) != out.end()) {
      ++*repeats;
      continue;
    }
    out.push_back(s);
  }
  return out;
}

std::vector<std::string> payloads(const std::vector<std::pair<std::string, std::string>>& in) {
  std::vector<std::string> out;
  for (const auto& [topic, payload] : in) out.push_back(payload);
  return out;
}

bool wait_connected(int metrics_port, const std::string& output) {
  return eventually(
      [&] {
        return metric(metrics_port, "leakmon_mqtt_connected{output=\"" + output + "\"}") == 1.0;
      },
      15s);
}

void reload_times(DaemonProcess& daemon, int count) {
  for (int i = 0; i < count; ++i) {
    daemon.signal(SIGHUP);
    std::this_thread::sleep_for(300ms);
  }
}

TEST(MqttBroker, DeliversEveryEventInOrderWithStatusBirthAndLastWill) {
  const std::string dir = scratch_dir("mqtt_broker_delivery");
  Broker broker(dir, free_port());
  Subscriber subscriber(broker.port(), dir + "/received.txt", "leakmon-test-delivery");
  const int metrics_port = free_port();
  write_file(dir + "/leakmon.yaml",
             daemon_config(metrics_port, 2, mqtt_output("fleet", broker.port())));
  DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml"}, dir + "/daemon.log");
  ASSERT_TRUE(wait_connected(metrics_port, "fleet")) << daemon.log();
  EXPECT_TRUE(eventually([&] { return retained_status(broker.port(), kTopic) == "online"; }, 10s));

  reload_times(daemon, 4);  // each reload is an event (config_reloaded), and a new output
  ASSERT_TRUE(wait_connected(metrics_port, "fleet")) << daemon.log();
  ASSERT_TRUE(eventually(
      [&] {
        const auto logged = lines_of(dir + "/events.jsonl");
        return logged.size() >= 4 && subscriber.messages("/event").size() >= logged.size();
      },
      20s))
      << daemon.log();
  const auto logged = lines_of(dir + "/events.jsonl");
  const auto events = subscriber.messages("/event");
  int repeats = 0;
  EXPECT_EQ(without_repeats(payloads(events), &repeats), logged);
  EXPECT_EQ(repeats, 0);  // the broker never went away: nothing to send twice
  for (const auto& [topic, payload] : events) {
    const bool has_actuator = payload.find("\"actuator\": \"cylinder\"") != std::string::npos;
    EXPECT_EQ(topic, has_actuator ? kTopic + "/cylinder/event" : kTopic + "/event") << payload;
  }
  const auto features = subscriber.messages("/features");
  ASSERT_FALSE(features.empty());
  EXPECT_EQ(features.back().first, kTopic + "/cylinder/features");
  EXPECT_TRUE(eventually(
      [&] {
        const std::string message = subscriber.messages("/features").back().second;
        return message.find("\"index_p1_pa\": ") != std::string::npos &&
               message.find("\"index\": ") != std::string::npos;  // the old name, one release
      },
      10s));
  EXPECT_EQ(metric(metrics_port, "leakmon_mqtt_queue_events{output=\"fleet\"}"), 0.0);

  // The daemon dies without a word: the broker publishes its last will, retained.
  daemon.signal(SIGKILL);
  daemon.wait(5s);
  EXPECT_TRUE(eventually([&] { return retained_status(broker.port(), kTopic) == "offline"; }, 10s));
  const auto status = subscriber.messages("/status");
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.front().second, "online");
  EXPECT_EQ(status.back().second, "offline");
}

TEST(MqttBroker, BrokerKilledAndRestartedMidRunLosesNoEventAndKeepsOrder) {
  const std::string dir = scratch_dir("mqtt_broker_restart");
  Broker broker(dir, free_port());
  auto subscriber =
      std::make_unique<Subscriber>(broker.port(), dir + "/received-1.txt", "leakmon-test-restart");
  const int metrics_port = free_port();
  write_file(dir + "/leakmon.yaml",
             daemon_config(metrics_port, 2, mqtt_output("fleet", broker.port())));
  DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml"}, dir + "/daemon.log");
  ASSERT_TRUE(wait_connected(metrics_port, "fleet")) << daemon.log();
  reload_times(daemon, 2);
  ASSERT_TRUE(eventually([&] { return subscriber->messages("/event").size() >= 2; }, 15s));

  broker.kill();
  subscriber.reset();
  ASSERT_TRUE(eventually(
      [&] { return metric(metrics_port, "leakmon_mqtt_connected{output=\"fleet\"}") == 0.0; },
      10s));
  const double processed = metric(metrics_port, "leakmon_samples_processed_total");
  reload_times(daemon, 3);  // events while the broker is away
  EXPECT_TRUE(eventually(
      [&] { return metric(metrics_port, "leakmon_mqtt_queue_events{output=\"fleet\"}") >= 3.0; },
      10s))
      << daemon.log();
  EXPECT_GT(metric(metrics_port, "leakmon_samples_processed_total"), processed + 100);

  broker.start();
  Subscriber again(broker.port(), dir + "/received-2.txt", "leakmon-test-restart");
  ASSERT_TRUE(wait_connected(metrics_port, "fleet")) << daemon.log();
  reload_times(daemon, 1);
  const std::string first = dir + "/received-1.txt";
  auto received = [&] {
    auto all = payloads(Subscriber::messages_in(first, "/event"));
    for (auto& p : payloads(again.messages("/event"))) all.push_back(p);
    return all;
  };
  int repeats = 0;
  ASSERT_TRUE(eventually(
      [&] {
        int ignored = 0;
        return without_repeats(received(), &ignored).size() >=
               lines_of(dir + "/events.jsonl").size();
      },
      20s))
      << daemon.log();
  const auto logged = lines_of(dir + "/events.jsonl");
  EXPECT_GE(logged.size(), 6u);
  EXPECT_EQ(without_repeats(received(), &repeats), logged);
  RecordProperty("repeated_messages", repeats);
  EXPECT_TRUE(eventually(
      [&] { return metric(metrics_port, "leakmon_mqtt_queue_events{output=\"fleet\"}") == 0.0; },
      10s));
}

TEST(MqttBroker, AnAbsentOrSilentBrokerNeverStallsTheDaemon) {
  const std::string dir = scratch_dir("mqtt_broker_absent");
  // A "broker" that completes TCP handshakes (the kernel's backlog) and never says a word.
  const int silent_fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(silent_fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ASSERT_EQ(::listen(silent_fd, 16), 0);
  socklen_t length = sizeof addr;
  ::getsockname(silent_fd, reinterpret_cast<sockaddr*>(&addr), &length);
  const int silent_port = ntohs(addr.sin_port);
  const int absent_port = free_port();  // nothing listens: connection refused

  const int metrics_port = free_port();
  write_file(dir + "/leakmon.yaml", daemon_config(metrics_port, 10,
                                                  mqtt_output("silent", silent_port) +
                                                      mqtt_output("absent", absent_port)));
  DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml"}, dir + "/daemon.log");
  ASSERT_TRUE(
      eventually([&] { return !std::isnan(metric(metrics_port, "leakmon_events_total")); }, 10s))
      << daemon.log();
  std::this_thread::sleep_for(1s);
  const std::string cycles = "leakmon_loop_cycles_total{group=\"main\"}";
  const std::string overruns = "leakmon_loop_overruns_total{group=\"main\"}";
  const std::string missed = "leakmon_loop_missed_cycles_total{group=\"main\"}";
  const double cycles_before = metric(metrics_port, cycles);
  const double overruns_before = metric(metrics_port, overruns);
  const double missed_before = metric(metrics_port, missed);
  const double processed_before = metric(metrics_port, "leakmon_samples_processed_total");
  reload_times(daemon, 3);
  std::this_thread::sleep_for(2s);
  const double cycles_after = metric(metrics_port, cycles);
  const double processed_after = metric(metrics_port, "leakmon_samples_processed_total");
  // About 330 periods of 10 ms passed; the loop and the worker kept up with all of them.
  EXPECT_GT(cycles_after - cycles_before, 150.0);
  EXPECT_GT(processed_after - processed_before, 0.9 * (cycles_after - cycles_before));
  EXPECT_EQ(metric(metrics_port, "leakmon_ring_drops_total{group=\"main\"}"), 0.0);
  // A connect that blocked the loop for the broker's 1 s timeout would miss about 100 periods of
  // 10 ms; a late wake-up or two on a loaded machine (a sanitizer build) is not a stall.
  EXPECT_LE(metric(metrics_port, overruns) - overruns_before, 2.0);
  EXPECT_LE(metric(metrics_port, missed) - missed_before, 2.0);
  for (const std::string output : {"silent", "absent"}) {
    const std::string label = "{output=\"" + output + "\"}";
    EXPECT_EQ(metric(metrics_port, "leakmon_mqtt_connected" + label), 0.0);
    EXPECT_GE(metric(metrics_port, "leakmon_mqtt_queue_events" + label), 3.0) << output;
    EXPECT_GT(metric(metrics_port, "leakmon_mqtt_features_dropped_total" + label), 0.0) << output;
    EXPECT_EQ(metric(metrics_port, "leakmon_mqtt_events_dropped_total" + label), 0.0) << output;
  }
  const std::string log = daemon.log();
  EXPECT_NE(log.find("mqtt output silent: broker 127.0.0.1:" + std::to_string(silent_port) +
                     ": no answer (CONNACK) within 1 s"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("mqtt output absent: broker 127.0.0.1:" + std::to_string(absent_port) +
                     ": cannot connect: Connection refused"),
            std::string::npos)
      << log;
  // Stopping does not wait on the broker either.
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(10s), 0) << daemon.log();
  ::close(silent_fd);
}

TEST(MqttBroker, RefusedCredentialsAndTlsFailuresAreClearErrors) {
  const std::string dir = scratch_dir("mqtt_broker_credentials");
  ChildProcess passwd({"mosquitto_passwd", "-b", "-c", dir + "/passwords", "rig1", "right"});
  ASSERT_EQ(passwd.stop_and_wait(0, 10.0), 0);
  Broker broker(dir, free_port(), "allow_anonymous false\npassword_file " + dir + "/passwords\n");
  const int metrics_port = free_port();
  auto config = [&](const std::string& password) {
    return daemon_config(
        metrics_port, 2,
        mqtt_output("fleet", broker.port(), ", username: rig1, password: " + password) +
            mqtt_output("tls", broker.port(),
                        ", tls: {ca_file: /etc/ssl/certs/ca-certificates.crt}"));
  };
  write_file(dir + "/leakmon.yaml", config("wrong"));
  DaemonProcess daemon({"run", "--config", dir + "/leakmon.yaml"}, dir + "/daemon.log");
  ASSERT_TRUE(eventually(
      [&] {
        return daemon.log().find(
                   "mqtt output fleet: broker 127.0.0.1:" + std::to_string(broker.port()) +
                   ": the broker refused the connection") != std::string::npos;
      },
      15s))
      << daemon.log();
  EXPECT_NE(daemon.log().find("check username and password"), std::string::npos) << daemon.log();
  EXPECT_TRUE(eventually(
      [&] {
        return daemon.log().find("mqtt output tls: broker 127.0.0.1:" +
                                 std::to_string(broker.port()) + " (TLS): ") != std::string::npos;
      },
      15s))
      << daemon.log();
  EXPECT_EQ(metric(metrics_port, "leakmon_mqtt_connected{output=\"fleet\"}"), 0.0);
  EXPECT_GE(metric(metrics_port, "leakmon_mqtt_connect_failures_total{output=\"fleet\"}"), 1.0);
  EXPECT_TRUE(daemon.running());

  // The right password, by reload: connected, and the queued events go out.
  write_file(dir + "/leakmon.yaml", config("right"));
  daemon.signal(SIGHUP);
  ASSERT_TRUE(wait_connected(metrics_port, "fleet")) << daemon.log();
  EXPECT_TRUE(eventually(
      [&] { return metric(metrics_port, "leakmon_mqtt_queue_events{output=\"fleet\"}") == 0.0; },
      10s));
  EXPECT_GE(metric(metrics_port, "leakmon_mqtt_events_published_total{output=\"fleet\"}"), 1.0);
  EXPECT_EQ(metric(metrics_port, "leakmon_mqtt_connected{output=\"tls\"}"), 0.0);
}

TEST(MqttBroker, CheckConfigNamesTheMqttFieldAtFileLineColumn) {
  const std::string dir = scratch_dir("mqtt_check_config");
  write_file(dir + "/leakmon.yaml",
             daemon_config(0, 2, mqtt_output("fleet", 1883, ", tls: {ca_file: missing.crt}")));
  DaemonProcess check({"check-config", dir + "/leakmon.yaml"}, dir + "/check.log");
  EXPECT_EQ(check.wait(20s), 1);
  const std::string out = check.log();
  EXPECT_NE(out.find(dir + "/leakmon.yaml:"), std::string::npos) << out;
  EXPECT_NE(out.find("outputs[0].tls.ca_file: file '" + dir + "/missing.crt' does not exist"),
            std::string::npos)
      << out;
  // Checking never connects: no queue directory appears.
  EXPECT_FALSE(std::filesystem::exists(dir + "/queue-fleet"));
}

}  // namespace
}  // namespace leakmon::test
