// Commissioning against a real Modbus peer (the pymodbus server of modbus_server.py): `leakmon
// probe` reads every channel once (or for --seconds) and prints it in SI units with its NE 107
// status, and `leakmon check-config` asks the peer whether it answers (issue 25: a configuration
// whose Modbus device did not answer passed the full pre-flight).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "tests/daemon/daemon_process.hpp"
#include "tests/io/modbus/peer_process.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::test {
namespace {

struct Invocation {
  int status = -1;
  std::string output;  // stdout and stderr
};

Invocation run(const std::string& arguments) {
  Invocation result;
  FILE* pipe = ::popen((leakmon_binary() + " " + arguments + " 2>&1").c_str(), "r");
  std::array<char, 4096> buffer{};
  while (pipe != nullptr && std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) {
    result.output += buffer.data();
  }
  const int status = pipe != nullptr ? ::pclose(pipe) : -1;
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// The served process: constant values, so that every value read is known exactly (all of them
// are exact in the registers' types: 86.5 bar in a FLOAT32, 1234 um in an INT16, ...).
constexpr double kP1 = 8.65e6, kP2 = 4.325e6, kX = 0.01234, kU = 2.5, kOil = 41.5, kSpare = 42;

std::string served_capture(const std::string& dir) {
  const std::string path = dir + "/served.csv";
  std::ofstream out(path);
  out << "# leakmon capture v1\n# sample_rate_hz: 500\nt,p1,p2,x,u,oil,spare\n";
  for (const char* t : {"0.000", "0.002"}) {
    out << t << "," << kP1 << "," << kP2 << "," << kX << "," << kU << "," << kOil << "," << kSpare
        << "\n";
  }
  return path;
}

ModbusServerOptions server_options(const std::string& dir) {
  ModbusServerOptions options;
  options.ready_file = dir + "/ready";
  options.capture = served_capture(dir);
  options.map =
      "p1:input:0:FLOAT32:ABCD:100000:0,p2:input:2:FLOAT32:ABCD:100000:0,"
      "x:input:4:INT16:ABCD:0.00001:0,u:holding:100:INT16:ABCD:0.001:0,"
      "oil:input:10:INT16:ABCD:0.01:0,spare:input:11:UINT16:ABCD:1:0";
  return options;
}

// The rig of config/leakmon.yaml on the test peer's port; `extra` goes under the actuator.
std::string write_config(const std::string& dir, const std::string& name, int port,
                         const std::string& extra_channels = "",
                         const std::string& extra_actuator = "") {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << "drivers:\n"
                         "  - name: daq\n"
                         "    type: modbus\n"
                         "    host: 127.0.0.1\n"
                         "    port: "
                      << port
                      << "\n"
                         "    timeout_ms: 200\n"
                         "    reconnect_min_ms: 50\n"
                         "    channels:\n"
                         "      - {name: p1, register: input, address: 0, data_type: FLOAT32, "
                         "scale: 100000}\n"
                         "      - {name: p2, register: input, address: 2, data_type: FLOAT32, "
                         "scale: 100000}\n"
                         "      - {name: x, register: input, address: 4, data_type: INT16, "
                         "scale: 0.00001}\n"
                         "      - {name: u, register: holding, address: 100, data_type: INT16, "
                         "scale: 0.001}\n"
                         "      - {name: oil, register: input, address: 10, data_type: INT16, "
                         "scale: 0.01}\n"
                         "      - {name: spare, register: input, address: 11}\n"
                      << extra_channels
                      << "sampling:\n"
                         "  - {name: main, period_ms: 2, drivers: [daq], priority: 0}\n"
                         "actuators:\n"
                         "  - name: cylinder\n"
                         "    channels: {p1: daq.p1, p2: daq.p2, u: daq.u, x: daq.x, temp: "
                         "daq.oil}\n"
                      << extra_actuator
                      << "state: {directory: state}\n"
                         "events: {log: events.jsonl}\n"
                         "metrics: {port: 0}\n";
  return path;
}

// `daq.NAME = VALUE ...` lines of probe's output: the value and the rest of the line.
std::map<std::string, std::pair<double, std::string>> probed_values(const std::string& output) {
  std::map<std::string, std::pair<double, std::string>> values;
  const std::regex line(R"(^  daq\.(\w+) = ([^\s;]+)(.*)$)");
  std::istringstream in(output);
  for (std::string text; std::getline(in, text);) {
    std::smatch m;
    if (std::regex_match(text, m, line)) values[m[1]] = {std::stod(m[2]), m[3]};
  }
  return values;
}

TEST(ModbusCommissioning, ProbePrintsEveryChannelOnceInSiUnitsWithItsStatus) {
  const std::string dir = scratch_dir("modbus_probe_once");
  ModbusServer server(server_options(dir));
  const std::string config = write_config(dir, "rig.yaml", server.port());

  const Invocation probe = run("probe --config " + config);
  EXPECT_EQ(probe.status, 0) << probe.output;
  EXPECT_NE(probe.output.find("daq (modbus): ok"), std::string::npos) << probe.output;
  const auto values = probed_values(probe.output);
  const std::map<std::string, std::pair<double, std::string>> expected{
      {"p1", {kP1, " Pa (8.650 MPa)  [ok]  cylinder.p1"}},
      {"p2", {kP2, " Pa (4.325 MPa)  [ok]  cylinder.p2"}},
      {"x", {kX, " m  [ok]  cylinder.x"}},
      {"u", {kU, " V  [ok]  cylinder.u"}},
      {"oil", {kOil, " degC  [ok]  cylinder.temp"}},
      {"spare", {kSpare, "  [ok]  (no actuator uses it)"}},
  };
  ASSERT_EQ(values.size(), expected.size()) << probe.output;
  for (const auto& [channel, want] : expected) {
    ASSERT_TRUE(values.count(channel)) << channel << "\n" << probe.output;
    const auto& [value, rest] = values.at(channel);
    EXPECT_NEAR(value, want.first, 1e-9 * std::abs(want.first) + 1e-12) << channel;
    EXPECT_EQ(rest, want.second) << channel;
  }
  EXPECT_NE(probe.output.find(config + ": 6 channel(s) ok"), std::string::npos) << probe.output;

  // For a while: every value is the served one, no gaps.
  const Invocation timed = run("probe --config " + config + " --seconds 1");
  EXPECT_EQ(timed.status, 0) << timed.output;
  const auto over_time = probed_values(timed.output);
  ASSERT_EQ(over_time.size(), expected.size()) << timed.output;
  const std::regex stats(
      R"(^[^;]*; min (\S+)[^,]*, max (\S+)[^,]*, mean (\S+)[^;]*; (\d+) values, (\d+) gaps  \[ok\].*$)");
  for (const auto& [channel, want] : expected) {
    const auto& [value, rest] = over_time.at(channel);
    EXPECT_NEAR(value, want.first, 1e-9 * std::abs(want.first) + 1e-12) << channel;
    std::smatch m;
    ASSERT_TRUE(std::regex_match(rest, m, stats)) << channel << ": " << rest;
    for (int k : {1, 2, 3}) {
      EXPECT_NEAR(std::stod(m[k]), want.first, 1e-9 * std::abs(want.first) + 1e-12) << channel;
    }
    // Read repeatedly (at the group's 500 Hz; how many a loaded machine manages is not this
    // test's business); values older than max_age count as gaps, never as values.
    EXPECT_GE(std::stoi(m[4]), 1) << channel;
    EXPECT_GE(std::stoi(m[4]) + std::stoi(m[5]), 2) << channel;
  }
}

TEST(ModbusCommissioning, ProbeFlagsValuesOutsideTheTransducerAndAPeerThatIsNotThere) {
  const std::string dir = scratch_dir("modbus_probe_faults");
  ModbusServer server(server_options(dir));
  // p1's transducer is configured for 0..5 MPa: 8.65 MPa is out of its specification.
  const std::string narrow = write_config(dir, "narrow.yaml", server.port(), "",
                                          "    transducers: {p1: {min: 0, max: 5.0e6}}\n");
  const Invocation probe = run("probe --config " + narrow);
  EXPECT_EQ(probe.status, 1) << probe.output;
  const auto values = probed_values(probe.output);
  ASSERT_TRUE(values.count("p1")) << probe.output;
  EXPECT_NE(values.at("p1").second.find("[out_of_specification: outside the transducer's range "
                                        "0 Pa (0.000 MPa) .. 5000000 Pa (5.000 MPa)]"),
            std::string::npos)
      << probe.output;
  EXPECT_NE(values.at("p2").second.find("[ok]"), std::string::npos) << probe.output;
  EXPECT_NE(probe.output.find("1 of 6 channel(s) or driver(s) not ok"), std::string::npos)
      << probe.output;

  // Nobody listens on this port: every channel is a failure, the driver says why.
  const std::string dead = write_config(dir, "dead.yaml", free_port());
  const Invocation nothing = run("probe --config " + dead + " --timeout 1");
  EXPECT_EQ(nothing.status, 1) << nothing.output;
  EXPECT_NE(nothing.output.find("daq (modbus): failure"), std::string::npos) << nothing.output;
  EXPECT_NE(nothing.output.find("  daq.p1 = -  [failure: no value within 1 s]  cylinder.p1"),
            std::string::npos)
      << nothing.output;
}

TEST(ModbusCommissioning, CheckConfigAsksThePeerAndWarnsOfOverlappingRegisters) {
  const std::string dir = scratch_dir("modbus_check_config_peer");
  ModbusServer server(server_options(dir));
  // p1 again on p2's registers: a copied entry whose address was not changed.
  const std::string config = write_config(
      dir, "rig.yaml", server.port(),
      "      - {name: p1b, register: input, address: 2, data_type: FLOAT32, scale: 100000}\n");
  const Invocation ok = run("check-config " + config);
  EXPECT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("warning: " + config +
                           ":15:47: drivers[0].channels[6].address: channel 'p1b' reads "
                           "registers 2..3 of unit 1, which channel 'p2' (" +
                           config + ":10:46) also reads"),
            std::string::npos)
      << ok.output;

  // The same rig whose device does not answer: the full pre-flight fails at the host.
  const int closed = free_port();
  const std::string dead = write_config(dir, "dead.yaml", closed);
  const Invocation refused = run("check-config " + dead);
  EXPECT_EQ(refused.status, 1) << refused.output;
  EXPECT_NE(refused.output.find(dead + ":4:11: drivers[0].host: Modbus device 127.0.0.1:" +
                                std::to_string(closed) + " does not answer: Connection refused"),
            std::string::npos)
      << refused.output;
  // ... which the service's start (ExecStartPre) and --no-probe leave out.
  EXPECT_EQ(run("check-config --no-peers " + dead).status, 0);
  EXPECT_EQ(run("check-config --no-probe " + dead).status, 0);

  // An address that is none fails however little is probed, with its location.
  std::string text = DaemonProcess::read_file(dead);
  text.replace(text.find("127.0.0.1"), 9, "127.0.0.300");
  std::ofstream(dir + "/typo.yaml") << text;
  const Invocation typo = run("check-config --no-probe " + dir + "/typo.yaml");
  EXPECT_EQ(typo.status, 1) << typo.output;
  EXPECT_NE(typo.output.find(dir + "/typo.yaml:4:11: drivers[0].host: '127.0.0.300' is not an "
                                   "IPv4 address"),
            std::string::npos)
      << typo.output;
}

}  // namespace
}  // namespace leakmon::test
