// What can be checked of the SocketCAN driver on a host whose kernel has no CAN: it builds from
// its configuration, reads gaps before start(), and start() fails with a message that names
// the interface and the cause instead of crashing. The socket itself is tested in the VM
// (tests/vm/can_vm_probe.cpp).
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/can/can_driver.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::io {
namespace {

std::unique_ptr<Driver> vcan_driver(const std::string& interface) {
  return make_can_driver(config::ConfigNode::load_string(
      "name: bus\ntype: can\ninterface: " + interface +
          "\nsignals:\n  - channel: p1\n    id: 0x101\n    length: 16\n",
      "bus.yaml"));
}

bool host_has_can() {
  const int fd = socket(PF_CAN, SOCK_RAW, 1 /* CAN_RAW */);
  if (fd < 0) return false;
  close(fd);
  return true;
}

// The controller's fault-confinement states as NAMUR NE 107 categories: frames still arrive
// while error-warning or error-passive (degrading), none when bus-off.
TEST(CanDriverHost, BusStatesMapOntoNe107) {
  EXPECT_EQ(can::device_status(can::BusState::active), DeviceStatus::ok);
  EXPECT_EQ(can::device_status(can::BusState::warning), DeviceStatus::maintenance_required);
  EXPECT_EQ(can::device_status(can::BusState::passive), DeviceStatus::maintenance_required);
  EXPECT_EQ(can::device_status(can::BusState::bus_off), DeviceStatus::failure);
}

TEST(CanDriverHost, ReadBeforeStartGivesGapsWithoutAllocating) {
  auto driver = vcan_driver("vcan0");
  std::vector<double> values(1, 0.0);
  test::AllocationScope scope;
  EXPECT_EQ(driver->read(Tick{0, 1'000'000}, values), ReadStatus::ok);
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_TRUE(std::isnan(values[0]));
}

TEST(CanDriverHost, StartFailsWithAClearErrorWhenTheSocketCannotBeHad) {
  // Without kernel CAN support socket() fails; with it, the made-up interface does not exist.
  auto driver = vcan_driver("nosuchcan9");
  try {
    driver->start();
    FAIL() << "start() succeeded on a missing interface";
  } catch (const DriverError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("nosuchcan9"), std::string::npos) << message;
    if (!host_has_can()) {
      EXPECT_NE(message.find("socket(PF_CAN"), std::string::npos) << message;
    } else {
      EXPECT_NE(message.find("no such interface"), std::string::npos) << message;
    }
  }
  EXPECT_EQ(driver->health().detail, "ok") << "a failed start is not a bus state";
  EXPECT_EQ(driver->health().status, DeviceStatus::ok);
}

}  // namespace
}  // namespace leakmon::io
