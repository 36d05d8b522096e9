// The driver over a serial line: a socat pseudo-terminal pair between the driver (RTU master)
// and the pymodbus server in serial RTU mode.
#include <gtest/gtest.h>

#include "config/yaml_reader.hpp"
#include "io/modbus/modbus_driver.hpp"
#include "tests/io/modbus/peer_process.hpp"
#include "tests/io/modbus/served_capture.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::test {
namespace {

TEST(ModbusRtu, SamplesEqualTheServedCaptureOverAPseudoTerminal) {
  const std::string dir = scratch_dir("ModbusRtu");
  const ServedCapture capture(dir, 1000);
  const PtyPair line(dir);
  ModbusServerOptions options;
  options.ready_file = dir + "/ready";
  options.serial = line.a();
  options.capture = capture.path();
  options.map = ServedCapture::server_map();
  ModbusServer server(options);

  const std::string yaml = "name: bus\ntype: modbus\ntransport: rtu\ndevice: " + line.b() +
                           "\nbaud: 115200\nparity: N\npoll_rate_hz: 100\ntimeout_ms: 200\n"
                           "max_age_ms: 100\n" +
                           ServedCapture::driver_channels();
  auto driver = io::make_modbus_driver(config::ConfigNode::load_string(yaml, "rtu.yaml"));
  driver->start();
  ServedCapture::Tally warmup;
  ASSERT_TRUE(capture.run_until_fresh(*driver, 10, 20.0, warmup)) << driver->health().last_error;
  const auto tally = capture.run(*driver, 1.0);
  EXPECT_EQ(warmup.mismatches + tally.mismatches, 0U)
      << warmup.first_mismatch << tally.first_mismatch;
  EXPECT_EQ(tally.allocations, 0U);
  EXPECT_GT(tally.fresh, 0U);
  EXPECT_EQ(driver->health().detail, "ok");
  EXPECT_EQ(driver->health().status, io::DeviceStatus::ok);
}

}  // namespace
}  // namespace leakmon::test
