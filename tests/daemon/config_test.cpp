// Configuration errors an operator can act on: file:line:column and the field, for unknown
// keys, wrong types, out-of-range values and references to things that do not exist.
#include "daemon/config.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "tests/support/paths.hpp"

namespace leakmon::daemon {
namespace {

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
  EXPECT_EQ(a.p1.driver, "rig");
  EXPECT_EQ(a.p1.channel, "p1");
  EXPECT_EQ(a.x.channel, "x");
  EXPECT_FALSE(a.p2.present());
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
  for (const char* file : {"/config/demo.yaml", "/io/sim/sim.yaml",
                           "/bench/daemon/rss_8_channels.yaml", "/io/mqtt/mqtt.yaml"}) {
    EXPECT_NO_THROW(check_config(test::source_dir() + file)) << file;
  }
  // The replay sample names a capture that only exists on a rig: parse it, do not build it.
  EXPECT_NO_THROW(load_config(test::source_dir() + "/io/replay/replay.yaml"));
}

}  // namespace
}  // namespace leakmon::daemon
