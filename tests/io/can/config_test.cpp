// Driver configuration: the sample YAML files beside the code load, and every mistake is
// reported at its file:line:column with the offending field named.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "config/yaml_reader.hpp"
#include "io/can/can_driver.hpp"
#include "io/can/signal_config.hpp"
#include "io/canlog/canlog_driver.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::io {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    make_can_driver(config::ConfigNode::load_string(yaml, "rig.yaml"));
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

const char* const kGood = R"(name: bus
type: can
interface: vcan0
signals:
  - channel: p1
    id: 0x101
    start_bit: 7
    length: 16
    byte_order: motorola
    factor: 5050
    unit: Pa
  - channel: x
    id: 418119424
    extended: true
    length: 32
    signed: true
    factor: 1.0e-6
    max_age: 0.1
)";

TEST(CanConfig, ReadsEveryField) {
  auto config = can::read_can_driver_config(config::ConfigNode::load_string(kGood, "rig.yaml"));
  EXPECT_EQ(config.name, "bus");
  EXPECT_EQ(config.socket.interface, "vcan0");
  EXPECT_FALSE(config.socket.fd);
  ASSERT_EQ(config.signals.size(), 2U);
  const auto& p1 = config.signals[0];
  EXPECT_EQ(p1.channel, "p1");
  EXPECT_EQ(p1.layout.id, 0x101U);
  EXPECT_FALSE(p1.layout.extended);
  EXPECT_EQ(p1.layout.byte_order, can::ByteOrder::motorola);
  EXPECT_EQ(p1.layout.start_bit, 7U);
  EXPECT_EQ(p1.layout.factor, 5050.0);
  EXPECT_EQ(p1.unit, "Pa");
  EXPECT_EQ(p1.max_age_ns, 20'000'000) << "driver default max age";
  const auto& x = config.signals[1];
  EXPECT_EQ(x.layout.id, 418119424U);
  EXPECT_TRUE(x.layout.extended);
  EXPECT_TRUE(x.layout.is_signed);
  EXPECT_EQ(x.max_age_ns, 100'000'000);
  auto driver = make_can_driver(config::ConfigNode::load_string(kGood, "rig.yaml"));
  ASSERT_EQ(driver->channels().size(), 2U);
  EXPECT_EQ(driver->channels()[1], "x");
  EXPECT_EQ(driver->name(), "bus");
}

TEST(CanConfig, ErrorsNameFileLineColumnAndField) {
  auto with = [](const std::string& from, const std::string& to) {
    std::string yaml = kGood;
    yaml.replace(yaml.find(from), from.size(), to);
    return error_of(yaml);
  };
  {
    const std::string e = with("id: 0x101", "id: 0x1G1");
    EXPECT_NE(e.find("rig.yaml:6:9"), std::string::npos) << e;
    EXPECT_NE(e.find("CAN identifier"), std::string::npos) << e;
  }
  {
    const std::string e = with("id: 0x101", "id: 0x801");
    EXPECT_NE(e.find("rig.yaml:6:9"), std::string::npos) << e;
    EXPECT_NE(e.find("11 bits"), std::string::npos) << e;
  }
  {
    const std::string e = with("byte_order: motorola", "byte_order: big");
    EXPECT_NE(e.find("rig.yaml:9:17"), std::string::npos) << e;
    EXPECT_NE(e.find("byte_order"), std::string::npos) << e;
  }
  {
    const std::string e = with("length: 16", "length: 65");
    EXPECT_NE(e.find("rig.yaml:8:13"), std::string::npos) << e;
  }
  {
    const std::string e = with("    unit: Pa", "    units: Pa");
    EXPECT_NE(e.find("rig.yaml:11"), std::string::npos) << e;
    EXPECT_NE(e.find("units"), std::string::npos) << e;
  }
  {
    const std::string e = with("channel: x", "channel: p1");
    EXPECT_NE(e.find("rig.yaml:12:14"), std::string::npos) << e;
    EXPECT_NE(e.find("twice"), std::string::npos) << e;
  }
  {
    const std::string e = with("factor: 5050", "factor: 0");
    EXPECT_NE(e.find("rig.yaml:10:13"), std::string::npos) << e;
  }
  {
    // Bytes 8..9 exist only in CAN FD frames.
    const std::string e = with("start_bit: 7", "start_bit: 71");
    EXPECT_NE(e.find("rig.yaml:7"), std::string::npos) << e;
    EXPECT_NE(e.find("fd: true"), std::string::npos) << e;
  }
  {
    const std::string e = with("interface: vcan0\n", "");
    EXPECT_NE(e.find("interface"), std::string::npos) << e;
  }
}

TEST(CanConfig, SampleFilesBesideTheCodeLoad) {
  auto can_driver =
      make_can_driver(config::ConfigNode::load_file(test::source_dir() + "/io/can/can.yaml"));
  EXPECT_FALSE(can_driver->channels().empty());
  auto canlog_driver = make_canlog_driver(
      config::ConfigNode::load_file(test::source_dir() + "/io/canlog/canlog.yaml"));
  EXPECT_EQ(canlog_driver->channels().size(), can_driver->channels().size());
  canlog_driver->start();  // the sample log parses
}

TEST(CanlogConfig, MissingLogFileIsNamedAtItsField) {
  try {
    make_canlog_driver(config::ConfigNode::load_string(
        "name: replay\ntype: canlog\nfile: /nonexistent/bus.log\nsignals:\n  - channel: p1\n"
        "    id: 0x101\n    length: 16\n",
        "replay.yaml"));
    FAIL() << "no error";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("replay.yaml:3:7"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/nonexistent/bus.log"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace leakmon::io
