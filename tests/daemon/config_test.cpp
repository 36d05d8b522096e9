// Configuration errors an operator can act on: file:line:column and the field, for unknown
// keys, wrong types, out-of-range values and references to things that do not exist.
#include "daemon/config.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>

#include "tests/support/paths.hpp"

namespace leakmon::daemon {
namespace {

using capture::Role;

std::string error_of(const std::string& yaml) {
  try {
    parse_config(config::ConfigNode::load_string(yaml, "rig.yaml"));
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

constexpr const char* kDriver = "drivers: [{name: rig, type: sim, scenario: healthy}]\n";

TEST(DaemonConfig, MinimalConfigGetsTheDocumentedDefaults) {
  const auto config = parse_config(config::ConfigNode::load_string(
      std::string(kDriver) + "actuators: [{name: a, channels: {p1: p1, x: rig.x}}]\n", "rig.yaml"));
  ASSERT_EQ(config.groups.size(), 1u);
  EXPECT_EQ(config.groups[0].period_ns, 2'000'000);
  EXPECT_EQ(config.groups[0].priority, 80);
  EXPECT_EQ(config.groups[0].drivers, std::vector<std::string>{"rig"});
  const auto& a = config.actuators.at(0);
  EXPECT_EQ(a.channels[Role::p1].driver, "rig");
  EXPECT_EQ(a.channels[Role::p1].channel, "p1");
  EXPECT_EQ(a.channels[Role::x].channel, "x");
  EXPECT_FALSE(a.channels[Role::p2].present());
  EXPECT_EQ(a.features.window, 400u);
  EXPECT_EQ(a.detector, "default");
  EXPECT_TRUE(std::isnan(a.alarm.raise_threshold)) << "left to the detector";
  EXPECT_EQ(config.metrics.port, 9187);
}

TEST(DaemonConfig, StateDirectoryDefaultsToSystemdsAndIsChecked) {
  const std::string actuator = "actuators: [{name: a, channels: {p1: p1}}]\n";
  ::setenv("STATE_DIRECTORY", "/run/first:/run/second", 1);
  const auto from_env =
      parse_config(config::ConfigNode::load_string(std::string(kDriver) + actuator, "rig.yaml"));
  EXPECT_EQ(from_env.state.directory, "/run/first");
  EXPECT_EQ(from_env.state.save_seconds, 60.0);
  ::unsetenv("STATE_DIRECTORY");
  const auto fallback =
      parse_config(config::ConfigNode::load_string(std::string(kDriver) + actuator, "rig.yaml"));
  EXPECT_EQ(fallback.state.directory, "/var/lib/leakmon");
  const auto relative = parse_config(config::ConfigNode::load_string(
      std::string(kDriver) + actuator + "state: {directory: kept, save_seconds: 5}\n",
      "/etc/leakmon/rig.yaml"));
  EXPECT_EQ(relative.state.directory, "/etc/leakmon/kept");
  EXPECT_EQ(relative.state.save_seconds, 5.0);
  const std::string error =
      error_of(std::string(kDriver) + actuator + "state: {save_seconds: 0.1}\n");
  EXPECT_NE(error.find("rig.yaml:3:"), std::string::npos) << error;
  EXPECT_NE(error.find("save_seconds"), std::string::npos) << error;
}

TEST(DaemonConfig, UnknownKeyNamesLineColumnAndPath) {
  const auto e = error_of(std::string(kDriver) +
                          "actuators:\n"
                          "  - name: a\n"
                          "    channels: {p1: p1}\n"
                          "    alarm: {raise: 2, clear: 1, latchng: true}\n");
  EXPECT_NE(e.find("rig.yaml:5:"), std::string::npos) << e;
  EXPECT_NE(e.find("latchng"), std::string::npos) << e;
}

TEST(DaemonConfig, WrongTypeAndOutOfRange) {
  auto e = error_of(std::string(kDriver) +
                    "sampling: [{name: g, drivers: [rig], period_ms: fast}]\n"
                    "actuators: [{name: a, channels: {p1: p1}}]\n");
  EXPECT_NE(e.find("rig.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("period_ms"), std::string::npos) << e;
  e = error_of(std::string(kDriver) +
               "sampling: [{name: g, drivers: [rig], priority: 120}]\n"
               "actuators: [{name: a, channels: {p1: p1}}]\n");
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  e = error_of(std::string(kDriver) + "actuators: [{name: a, channels: {p1: p1}}]\n" +
               "metrics: {port: 70000}\n");
  EXPECT_NE(e.find("rig.yaml:3:"), std::string::npos) << e;
}

TEST(DaemonConfig, DeadbandMustBeADeadband) {
  const auto e =
      error_of(std::string(kDriver) +
               "actuators: [{name: a, channels: {p1: p1}, alarm: {raise: 1, clear: 2}}]\n");
  EXPECT_NE(e.find("deadband"), std::string::npos) << e;
}

// Issue 23: how long a detector may not judge before the daemon says so; default 600 s, checked
// at its key.
TEST(DaemonConfig, NotJudgedEventSecondsIsReadAndChecked) {
  const auto defaults = parse_config(config::ConfigNode::load_string(
      std::string(kDriver) + "actuators: [{name: a, channels: {p1: p1}}]\n", "rig.yaml"));
  EXPECT_EQ(defaults.actuators.at(0).alarm.not_judged_event_seconds, 600.0);
  const auto set = parse_config(config::ConfigNode::load_string(
      std::string(kDriver) +
          "actuators: [{name: a, channels: {p1: p1}, alarm: {not_judged_event_seconds: 120}}]\n",
      "rig.yaml"));
  EXPECT_EQ(set.actuators.at(0).alarm.not_judged_event_seconds, 120.0);
  const auto e = error_of(
      std::string(kDriver) +
      "actuators: [{name: a, channels: {p1: p1}, alarm: {not_judged_event_seconds: -5}}]\n");
  EXPECT_NE(e.find("rig.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("not_judged_event_seconds"), std::string::npos) << e;
}

TEST(DaemonConfig, ReferencesMustExist) {
  EXPECT_NE(error_of(std::string(kDriver) + "actuators: [{name: a, channels: {p1: pump.p1}}]\n")
                .find("no driver named 'pump'"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kDriver) + "sampling: [{name: g, drivers: [rig, rig2]}]\n"
                                            "actuators: [{name: a, channels: {p1: p1}}]\n")
                .find("no driver named 'rig2'"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kDriver) +
                     "actuators: [{name: a, channels: {p1: p1}, detector: psychic}]\n")
                .find("unknown detector 'psychic'"),
            std::string::npos);
  EXPECT_NE(error_of(std::string(kDriver) +
                     "actuators: [{name: a, channels: {p1: p1}}, {name: a, channels: {p1: p2}}]\n")
                .find("duplicate actuator name 'a'"),
            std::string::npos);
}

TEST(DaemonConfig, OneActuatorIsSampledByOneGroup) {
  const auto e = error_of(
      "drivers: [{name: r1, type: sim, scenario: healthy}, {name: r2, type: sim, scenario: "
      "healthy}]\n"
      "sampling: [{name: g1, drivers: [r1]}, {name: g2, drivers: [r2]}]\n"
      "actuators: [{name: a, channels: {p1: r1.p1, p2: r2.p2}}]\n");
  EXPECT_NE(e.find("one sampling group"), std::string::npos) << e;
}

TEST(DaemonConfig, CheckConfigFindsMissingChannelsAndBadDriverTypes) {
  const std::string dir = test::scratch_dir("daemon_config_check");
  std::ofstream(dir + "/a.yaml") << kDriver << "actuators: [{name: a, channels: {p1: rig.p3}}]\n";
  try {
    check_config(dir + "/a.yaml");
    FAIL() << "missing channel accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("a.yaml:2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no channel 'p3'"), std::string::npos) << e.what();
  }
  std::ofstream(dir + "/b.yaml") << "drivers: [{name: rig, type: telepathy}]\n"
                                    "actuators: [{name: a, channels: {p1: rig.p1}}]\n";
  try {
    check_config(dir + "/b.yaml");
    FAIL() << "unknown driver type accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("b.yaml:1:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("unknown driver type 'telepathy'"), std::string::npos);
  }
  std::ofstream(dir + "/c.yaml")
      << "drivers: [{name: rig, type: sim, scenario: healthy, leak: {onset_s: 3}}]\n"
         "actuators: [{name: a, channels: {p1: rig.p1}}]\n";
  EXPECT_THROW(check_config(dir + "/c.yaml"), config::ConfigError) << "leak without a size";
}

TEST(DaemonConfig, ShippedExamplesAreValid) {
  // Examples without `state:` use $STATE_DIRECTORY, which the pre-flight checks is writable.
  ::setenv("STATE_DIRECTORY", test::scratch_dir("config_examples_state").c_str(), 1);
  for (const char* file :
       {"/config/demo.yaml", "/io/sim/sim.yaml", "/bench/daemon/rss_8_channels.yaml",
        "/io/replay/replay.yaml", "/io/mqtt/mqtt.yaml"}) {
    // The file itself and its paths; the port may be taken by a concurrent test.
    EXPECT_NO_THROW(check_config(test::source_dir() + file, Preflight{true, false})) << file;
  }
}

// What `run` checks before it acquires, check-config checks too (one function): each failure
// names file:line:column.
std::string preflight_error(const std::string& dir, const std::string& name,
                            const std::string& yaml, Preflight preflight = {}) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << yaml;
  try {
    check_config(path, preflight);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

constexpr const char* kBase =
    "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
    "actuators: [{name: a, channels: {p1: p1}}]\n"
    "state: {directory: ''}\n";

// Issue 25: leak sizes in the unit a rig engineer reads (l/min/MPa), where the configuration
// takes one; the detector still receives m^3/(s Pa), and mistakes name file:line:column.
TEST(DaemonConfig, LeakSizesMayBeGivenInLitresPerMinutePerMegapascal) {
  const std::string actuator =
      "actuators:\n"
      "  - name: a\n"
      "    channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x}\n"
      "    detector:\n"
      "      kind: flow_balance\n"
      "      options:\n";
  const auto config =
      parse_config(config::ConfigNode::load_string(std::string(kDriver) + actuator +
                                                       "        min_leak: 0.03 l/min/MPa\n"
                                                       "        design_leak: 0.015l/min/MPa\n"
                                                       "        learn_seconds: 30\n",
                                                   "rig.yaml"));
  const auto& options = *config.actuators.at(0).detector_options;
  EXPECT_NEAR(options.at("min_leak").as_double(), 5e-13, 1e-27);
  EXPECT_NEAR(options.at("design_leak").as_double(), 2.5e-13, 1e-27);
  EXPECT_EQ(options.at("learn_seconds").as_double(), 30.0);
  // The detector is built from them, as check-config does.
  std::vector<std::vector<std::string>> channels{{"p1", "p2", "u", "x"}};
  EXPECT_NO_THROW(check_channels(config, channels));
  EXPECT_EQ(error_of(std::string(kDriver) + actuator + "        learn_seconds: 3 l/min/MPa\n"),
            "rig.yaml:8:24: actuators[0].detector.options.learn_seconds: learn_seconds is not a "
            "leak size (l/min/MPa applies to design_leak and min_leak)");
  EXPECT_EQ(error_of(std::string(kDriver) + actuator + "        min_leak: lots l/min/MPa\n"),
            "rig.yaml:8:19: actuators[0].detector.options.min_leak: expected a number followed "
            "by l/min/MPa (e.g. 0.03 l/min/MPa), got 'lots l/min/MPa'");
  EXPECT_NE(error_of(std::string(kDriver) + actuator + "        min_leak: 0.03 l/min/MPa/s\n")
                .find("expected a number followed by l/min/MPa"),
            std::string::npos);
}

TEST(DaemonConfig, MetricsAddressMustBeAnIpv4Address) {
  const std::string dir = test::scratch_dir("config_preflight_address");
  for (const char* address : {"256.1.1.1", "localhost", "1.2.3", "::1"}) {
    const std::string e = preflight_error(
        dir, "a.yaml", std::string(kBase) + "metrics: {address: '" + address + "'}\n");
    EXPECT_NE(e.find("a.yaml:4:20: metrics.address: '" + std::string(address) +
                     "' is not an IPv4 address"),
              std::string::npos)
        << e;
  }
  EXPECT_EQ(
      preflight_error(dir, "b.yaml", std::string(kBase) + "metrics: {address: 0.0.0.0, port: 0}\n"),
      "no error");
}

TEST(DaemonConfig, MetricsPortInUseIsAnError) {
  const std::string dir = test::scratch_dir("config_preflight_port");
  // Hold a listening socket on a port the kernel chose.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  ASSERT_EQ(::listen(fd, 1), 0);
  socklen_t length = sizeof(addr);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &length);
  const std::string yaml =
      std::string(kBase) + "metrics: {port: " + std::to_string(ntohs(addr.sin_port)) + "}\n";
  const std::string e = preflight_error(dir, "a.yaml", yaml);
  EXPECT_NE(e.find("a.yaml:4:17: metrics.port: cannot listen on 127.0.0.1:"), std::string::npos)
      << e;
  EXPECT_NE(e.find("in use"), std::string::npos) << e;
  EXPECT_EQ(preflight_error(dir, "a.yaml", yaml, Preflight{false, false}), "no error");
  ::close(fd);
  EXPECT_EQ(preflight_error(dir, "a.yaml", yaml), "no error") << "free again";
}

TEST(DaemonConfig, PathsMustBeWritableAndOfTheRightKind) {
  const std::string dir = test::scratch_dir("config_preflight_paths");
  std::ofstream(dir + "/plain-file") << "x";
  const std::string is_dir =
      preflight_error(dir, "a.yaml", std::string(kBase) + "events: {log: " + dir + "}\n");
  EXPECT_NE(is_dir.find("a.yaml:4:15: events.log: event log '" + dir + "' is a directory"),
            std::string::npos)
      << is_dir;
  const std::string under_file = preflight_error(
      dir, "b.yaml", std::string(kBase) + "events: {log: plain-file/events.jsonl}\n");
  EXPECT_NE(under_file.find("b.yaml:4:15: events.log:"), std::string::npos) << under_file;
  EXPECT_NE(under_file.find("is not a directory"), std::string::npos) << under_file;
  const std::string recording =
      preflight_error(dir, "c.yaml", std::string(kBase) + "recording: {directory: plain-file}\n");
  EXPECT_NE(recording.find("c.yaml:4:24: recording.directory: recording directory"),
            std::string::npos)
      << recording;
  const std::string state = preflight_error(dir, "d.yaml",
                                            "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
                                            "actuators: [{name: a, channels: {p1: p1}}]\n"
                                            "state: {directory: plain-file/kept}\n");
  EXPECT_NE(state.find("d.yaml:3:20: state.directory:"), std::string::npos) << state;
  // Missing directories that can be created are fine: the daemon creates them.
  EXPECT_EQ(preflight_error(dir, "e.yaml",
                            std::string(kBase) + "events: {log: new/sub/events.jsonl}\n"
                                                 "recording: {directory: new/captures}\n"),
            "no error");
}

TEST(DaemonConfig, CanInterfaceMustExistUnlessNotProbed) {
  const std::string dir = test::scratch_dir("config_preflight_device");
  const std::string yaml =
      "drivers:\n"
      "  - {name: bus, type: can, interface: lmnone9,\n"
      "     signals: [{channel: p1, id: 0x101, start_bit: 0, length: 16, factor: 500}]}\n"
      "actuators: [{name: a, channels: {p1: p1}}]\n"
      "state: {directory: ''}\n"
      "metrics: {port: 0}\n";
  const std::string e = preflight_error(dir, "a.yaml", yaml);
  EXPECT_NE(e.find("a.yaml:2:39: drivers[0].interface: no network interface 'lmnone9'"),
            std::string::npos)
      << e;
  EXPECT_EQ(preflight_error(dir, "a.yaml", yaml, Preflight{false, true}), "no error");
}

TEST(DaemonConfig, DirectoryGivenAsTheConfigurationIsNamedAsSuch) {
  const std::string dir = test::scratch_dir("config_preflight_directory");
  try {
    check_config(dir);
    ADD_FAILURE() << "a directory was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              dir + ": is a directory, not a configuration file (name the YAML file in it)");
  }
}

TEST(DaemonConfig, DuplicateKeysAnywhereAreErrors) {
  EXPECT_EQ(error_of("drivers: [{name: rig, type: sim, scenario: healthy, seed: 7, seed: 8}]\n"
                     "actuators: [{name: a, channels: {p1: p1}}]\n"),
            "rig.yaml:1:62: duplicate key 'seed' (first given at line 1, column 53); only one "
            "of them would take effect");
  EXPECT_EQ(error_of(std::string(kDriver) + "actuators: [{name: a, channels: {p1: p1}}]\n"
                                            "metrics:\n  port: 9100\n"
                                            "metrics:\n  port: 9200\n"),
            "rig.yaml:5:1: duplicate key 'metrics' (first given at line 3, column 1); only one "
            "of them would take effect");
  // The same key in different mappings is no duplicate.
  EXPECT_EQ(error_of(std::string(kDriver) +
                     "actuators: [{name: a, channels: {p1: p1}}, {name: b, channels: {p1: p2}}]\n"),
            "no error");
}

TEST(DaemonConfig, NamesWithControlCharactersAreRejectedAndEscaped) {
  const std::string e = error_of(
      "drivers: [{name: \"r\\e[31mig\", type: sim, scenario: healthy}]\n"
      "actuators: [{name: a, channels: {p1: p1}}]\n");
  EXPECT_NE(e.find("must be printable text"), std::string::npos) << e;
  EXPECT_EQ(e.find('\x1b'), std::string::npos) << "raw ESC in the message";
  EXPECT_NE(e.find("r\\x1b[31mig"), std::string::npos) << e;
}

}  // namespace
}  // namespace leakmon::daemon

namespace leakmon::daemon {
namespace {

// An actuator's `rig:` (FORMATS.md): read with the one rig reader, its supply sets the pressure
// transducers' default range, and a value given both there and in the detector's options is
// valid but warned about, naming both places.
TEST(DaemonConfig, AnActuatorsRigIsReadAndSetsTheTransducersRange) {
  const auto config = parse_config(config::ConfigNode::load_string(
      std::string(kDriver) +
          "actuators:\n"
          "  - name: a\n"
          "    channels: {p1: p1, p2: p2}\n"
          "    rig: {bore: 0.05, rod: 0.028, supply_pressure: 21.0e6, valve_coefficient: 5.3e-7}\n"
          "  - name: b\n"
          "    channels: {p1: p1}\n"
          "    rig: {supply_pressure: 21.0e6}\n"
          "    transducers: {p1: {max: 40.0e6}}\n"
          "  - name: c\n"
          "    channels: {p1: p1}\n",
      "rig.yaml"));
  const auto& a = config.actuators.at(0);
  EXPECT_EQ(a.rig.stated,
            (std::vector<std::string>{"bore", "rod", "supply_pressure", "valve_coefficient"}));
  EXPECT_DOUBLE_EQ(a.rig.params.ps, 21.0e6);
  EXPECT_DOUBLE_EQ(a.rig.params.Kv, 5.3e-7);
  EXPECT_EQ(a.rig.source, "rig.yaml:5:10");
  // 21 MPa: the 25 MPa range (sim::sensors_for), 12 bit, for both chambers.
  EXPECT_DOUBLE_EQ(a.transducers[capture::Role::p1].max, 25e6);
  EXPECT_DOUBLE_EQ(a.transducers[capture::Role::p2].resolution, 25e6 / 4096.0);
  // A configured transducer range wins; without a rig, MODEL.md's 20.7 MPa.
  EXPECT_DOUBLE_EQ(config.actuators.at(1).transducers[capture::Role::p1].max, 40e6);
  EXPECT_DOUBLE_EQ(config.actuators.at(1).transducers[capture::Role::p2].max, 25e6);
  EXPECT_TRUE(config.actuators.at(2).rig.nominal());
  EXPECT_DOUBLE_EQ(config.actuators.at(2).transducers[capture::Role::p1].max, 20.7e6);
  EXPECT_TRUE(config.warnings.empty());

  const std::string e = error_of(std::string(kDriver) +
                                 "actuators:\n"
                                 "  - name: a\n"
                                 "    channels: {p1: p1}\n"
                                 "    rig:\n"
                                 "      bore: 0.05\n"
                                 "      supply: 21.0e6\n");
  EXPECT_NE(e.find("rig.yaml:7:15"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown rig key 'supply'"), std::string::npos) << e;
}

TEST(DaemonConfig, AValueInBothTheRigAndTheDetectorOptionsIsWarnedAboutWithBothPlaces) {
  const auto config = parse_config(config::ConfigNode::load_string(
      std::string(kDriver) + "actuators:\n"
                             "  - name: a\n"
                             "    channels: {p1: p1, p2: p2, u: u, x: x}\n"
                             "    rig:\n"
                             "      bore: 0.05\n"
                             "      supply_pressure: 21.0e6\n"
                             "      valve_rated_flow: 1.0e-3\n"
                             "      valve_rated_pressure_drop: 7.0e6\n"
                             "    detector:\n"
                             "      kind: flow_balance\n"
                             "      options:\n"
                             "        supply_pressure: 20.0e6\n"
                             "        valve_coefficient: 5.0e-7\n"
                             "        piston_area: 1.3e-3\n"
                             "        min_leak: 1.0e-13\n",
      "rig.yaml"));
  ASSERT_EQ(config.warnings.size(), 3u);
  const std::string& supply = config.warnings[0];
  EXPECT_EQ(supply.rfind("rig.yaml:13:26: ", 0), 0u) << supply;
  EXPECT_NE(supply.find("supply_pressure at rig.yaml:7:24"), std::string::npos) << supply;
  EXPECT_NE(supply.find("actuator 'a'"), std::string::npos) << supply;
  EXPECT_NE(config.warnings[1].find("valve_rated_flow at rig.yaml:8:25"), std::string::npos)
      << config.warnings[1];
  // The piston area restates the bore (the rod is the paper's, unstated).
  EXPECT_NE(config.warnings[2].find("bore at rig.yaml:6:13"), std::string::npos)
      << config.warnings[2];
  EXPECT_EQ(config.warnings[2].find("rod at"), std::string::npos) << config.warnings[2];
}

}  // namespace
}  // namespace leakmon::daemon
