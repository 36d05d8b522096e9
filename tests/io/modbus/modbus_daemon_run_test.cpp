// End to end: `leakmon run` with a Modbus driver against the pymodbus server serving a healthy
// simulated capture, while the server is killed and restarted, answers slowly and refuses
// requests. The daemon must keep running, record the served values exactly (gaps where the
// link failed, never stale or zero values), and raise no leak alarm because of the faults.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "capture/capture.hpp"
#include "tests/io/modbus/peer_process.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::test {
namespace {

void sleep_s(double seconds) {
  std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(seconds * 1e3)));
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(ModbusDaemonRun, FaultsGiveGapsNotAlarmsAndTheRecordingEqualsTheServedCapture) {
  const std::string dir = scratch_dir("ModbusDaemonRun");
  const std::string served = dir + "/healthy.csv";
  ASSERT_EQ(std::system((leakmon_binary() + " sim --preset healthy --seed 11 --out " + served +
                         " > " + dir + "/sim.log 2>&1")
                            .c_str()),
            0)
      << read_text(dir + "/sim.log");
  const capture::Capture capture = capture::read_capture(served);

  ModbusServerOptions options;
  options.ready_file = dir + "/ready";
  options.capture = served;
  options.map =
      "index:holding:0:UINT32:ABCD:1:0,p1:holding:2:FLOAT32:ABCD:1:0,"
      "p2:holding:4:FLOAT32:ABCD:1:0,x:holding:6:FLOAT32:CDAB:1:0,u:holding:8:FLOAT32:CDAB:1:0";
  auto server = std::make_unique<ModbusServer>(options);
  const int port = server->port();

  const std::string config = dir + "/leakmon.yaml";
  std::ofstream(config) << "drivers:\n"
                           "  - name: daq\n"
                           "    type: modbus\n"
                           "    host: 127.0.0.1\n"
                           "    port: "
                        << port
                        << "\n"
                           "    timeout_ms: 50\n"
                           "    reconnect_min_ms: 50\n"
                           "    reconnect_max_ms: 400\n"
                           "    max_age_ms: 20\n"
                           "    channels:\n"
                           "      - {name: index, address: 0, data_type: UINT32}\n"
                           "      - {name: p1, address: 2, data_type: FLOAT32}\n"
                           "      - {name: p2, address: 4, data_type: FLOAT32}\n"
                           "      - {name: x, address: 6, data_type: FLOAT32, byte_order: CDAB}\n"
                           "      - {name: u, address: 8, data_type: FLOAT32, byte_order: CDAB}\n"
                           "sampling:\n"
                           "  - {name: main, period_ms: 2, drivers: [daq], priority: 0}\n"
                           "actuators:\n"
                           "  - name: cylinder\n"
                           "    channels: {p1: daq.p1, p2: daq.p2, u: daq.u, x: daq.x}\n"
                           "    detector:\n"
                           "      kind: default\n"
                           "      options: {settle_seconds: 2, learn_seconds: 8}\n"
                           "events:\n"
                           "  log: events.jsonl\n"
                           "recording:\n"
                           "  directory: recording\n"
                           "  flush_seconds: 0.1\n"
                           "metrics:\n"
                           "  port: 0\n";
  ChildProcess daemon({leakmon_binary(), "run", "--config", config}, dir + "/daemon.log");

  sleep_s(12.0);  // settle and learn the healthy index from Modbus samples
  server->kill();
  sleep_s(1.5);
  server = std::make_unique<ModbusServer>([&] {
    ModbusServerOptions again = options;
    again.tcp_port = port;
    return again;
  }());
  sleep_s(2.0);
  server->toggle_slow();
  sleep_s(1.0);
  server->toggle_slow();
  sleep_s(2.0);
  server->toggle_exceptions();
  sleep_s(1.0);
  server->toggle_exceptions();
  sleep_s(4.0);
  EXPECT_EQ(daemon.stop_and_wait(SIGTERM, 20.0), 0) << read_text(dir + "/daemon.log");

  const std::string events = read_text(dir + "/events.jsonl");
  EXPECT_EQ(events.find("alarm_raised"), std::string::npos) << events;

  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir + "/recording"))
    files.push_back(entry.path().string());
  ASSERT_EQ(files.size(), 1U);
  const capture::Capture recorded = capture::read_capture(files.front());
  const auto& index = recorded.column("index");
  std::size_t matched = 0;
  std::size_t gaps = 0;
  std::size_t mismatched = 0;
  for (std::size_t i = 0; i < recorded.rows(); ++i) {
    if (std::isnan(index[i])) {
      ++gaps;
      for (const char* name : {"p1", "p2", "x", "u"})
        if (!std::isnan(recorded.column(name)[i])) ++mismatched;  // one request: all or none
      continue;
    }
    const auto row = static_cast<std::size_t>(index[i]) % capture.rows();
    for (const char* name : {"p1", "p2", "x", "u"}) {
      const double served_value = static_cast<float>(capture.column(name)[row]);
      if (recorded.column(name)[i] != served_value) ++mismatched;
    }
    ++matched;
  }
  EXPECT_EQ(mismatched, 0U);
  EXPECT_GT(matched, recorded.rows() / 3);  // the rest: the outage and CPU starvation
  EXPECT_GT(gaps, 0U);                      // the outage shows as gaps
}

}  // namespace
}  // namespace leakmon::test
