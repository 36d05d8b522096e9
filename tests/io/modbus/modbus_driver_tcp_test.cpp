// The driver against a real peer: Debian's pymodbus server on loopback, serving a capture.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <thread>

#include "config/yaml_reader.hpp"
#include "io/modbus/modbus_driver.hpp"
#include "tests/io/modbus/peer_process.hpp"
#include "tests/io/modbus/served_capture.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::test {
namespace {

constexpr double kMaxAgeMs = 20.0;

std::unique_ptr<io::Driver> make_driver(int port, const std::string& extra = "") {
  const std::string yaml =
      "name: daq\ntype: modbus\nhost: 127.0.0.1\nport: " + std::to_string(port) +
      "\npoll_rate_hz: 500\ntimeout_ms: 50\nmax_age_ms: 20\n"
      "reconnect_min_ms: 50\nreconnect_max_ms: 500\n" +
      extra + ServedCapture::driver_channels();
  return io::make_modbus_driver(config::ConfigNode::load_string(yaml, "test.yaml"));
}

class ModbusTcp : public ::testing::Test {
 protected:
  ModbusTcp()
      : dir_(scratch_dir(::testing::UnitTest::GetInstance()->current_test_info()->name())),
        capture_(dir_, 1000) {}

  ModbusServerOptions options(int port = 0) const {
    ModbusServerOptions o;
    o.ready_file = dir_ + "/ready";
    o.tcp_port = port;
    o.capture = capture_.path();
    o.map = ServedCapture::server_map();
    return o;
  }

  std::string dir_;
  ServedCapture capture_;
};

TEST_F(ModbusTcp, SamplesEqualTheServedCaptureAfterScaling) {
  ModbusServer server(options());
  auto driver = make_driver(server.port());
  ASSERT_EQ(driver->channels().size(), 7U);
  EXPECT_EQ(driver->channels()[1], "p1");
  driver->start();
  ServedCapture::Tally warmup;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, warmup));

  const auto tally = capture_.run(*driver, 1.5);
  EXPECT_EQ(tally.mismatches, 0U) << tally.first_mismatch;
  EXPECT_EQ(warmup.mismatches, 0U) << warmup.first_mismatch;
  EXPECT_EQ(tally.allocations, 0U);
  // Most ticks see fresh values; the rest are gaps, never stale or wrong numbers.
  EXPECT_GT(tally.fresh, tally.ticks / 4);
  const auto health = driver->health();
  EXPECT_EQ(health.detail, "ok");
  EXPECT_EQ(health.status, io::DeviceStatus::ok);
  EXPECT_EQ(health.reconnects, 0U);
  driver->stop();
  driver->stop();  // idempotent
}

TEST_F(ModbusTcp, ServerKilledAndRestartedGivesGapsThenRecovers) {
  auto server = std::make_unique<ModbusServer>(options());
  const int port = server->port();
  auto driver = make_driver(port);
  driver->start();
  ServedCapture::Tally before;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, before));

  server->kill();
  const std::int64_t killed_ns = monotonic_ns();
  // Nothing can arrive after the kill, so nothing may be read once it is older than max age.
  const auto outage =
      capture_.run(*driver, 0.5, killed_ns + static_cast<std::int64_t>(kMaxAgeMs * 1e6));
  EXPECT_EQ(outage.values_after_deadline, 0U);
  EXPECT_GT(outage.gaps, outage.ticks / 2);
  auto health = driver->health();
  EXPECT_EQ(health.detail, "disconnected");
  EXPECT_EQ(health.status, io::DeviceStatus::failure);
  EXPECT_GT(health.errors, 0U);
  EXPECT_GT(health.stale_values, 0U);

  server = std::make_unique<ModbusServer>(options(port));
  ServedCapture::Tally after;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, after));
  const auto settled = capture_.run(*driver, 0.5);
  EXPECT_EQ(before.mismatches + outage.mismatches + after.mismatches + settled.mismatches, 0U)
      << before.first_mismatch << outage.first_mismatch << after.first_mismatch
      << settled.first_mismatch;
  EXPECT_GT(settled.fresh, 0U);
  health = driver->health();
  EXPECT_EQ(health.detail, "ok");
  EXPECT_EQ(health.status, io::DeviceStatus::ok);
  EXPECT_GE(health.reconnects, 1U);
}

TEST_F(ModbusTcp, SlowServerTimesOutReconnectsAndNeverMixesUpAnswers) {
  ModbusServer server(options());
  auto driver = make_driver(server.port());
  driver->start();
  ServedCapture::Tally before;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, before));
  const auto errors_before = driver->health().errors;

  server.toggle_slow();  // every answer now takes 200 ms; the driver waits 50 ms
  const std::int64_t slowed_ns = monotonic_ns();
  // A poll in flight at the toggle may still succeed; after that, only timeouts.
  const auto slow = capture_.run(*driver, 1.0, slowed_ns + 100'000'000);
  EXPECT_EQ(slow.values_after_deadline, 0U);
  const auto health = driver->health();
  EXPECT_NE(health.detail, "ok");
  EXPECT_NE(health.status, io::DeviceStatus::ok);
  EXPECT_GT(health.errors, errors_before);
  EXPECT_NE(health.last_error.find("timeout"), std::string::npos) << health.last_error;

  server.toggle_slow();
  ServedCapture::Tally after;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, after));
  // Late answers to abandoned requests must not be taken for new ones.
  const auto settled = capture_.run(*driver, 0.5);
  EXPECT_EQ(before.mismatches + slow.mismatches + after.mismatches + settled.mismatches, 0U)
      << before.first_mismatch << slow.first_mismatch << after.first_mismatch
      << settled.first_mismatch;
  EXPECT_GE(driver->health().reconnects, 1U);
}

TEST_F(ModbusTcp, ExceptionRepliesGiveGapsAndKeepTheConnection) {
  ModbusServer server(options());
  auto driver = make_driver(server.port());
  driver->start();
  ServedCapture::Tally before;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, before));

  server.toggle_exceptions();
  const std::int64_t refused_ns = monotonic_ns();
  const auto refused = capture_.run(*driver, 0.5, refused_ns + 50'000'000);
  EXPECT_EQ(refused.values_after_deadline, 0U);
  auto health = driver->health();
  EXPECT_EQ(health.detail, "degraded");
  EXPECT_EQ(health.status, io::DeviceStatus::maintenance_required);
  EXPECT_EQ(health.reconnects, 0U);
  EXPECT_NE(health.last_error.find("exception"), std::string::npos) << health.last_error;
  const auto errors = health.errors;
  EXPECT_GT(errors, 0U);

  server.toggle_exceptions();
  ServedCapture::Tally after;
  ASSERT_TRUE(capture_.run_until_fresh(*driver, 10, 15.0, after));
  EXPECT_EQ(before.mismatches + refused.mismatches + after.mismatches, 0U)
      << before.first_mismatch << refused.first_mismatch << after.first_mismatch;
  health = driver->health();
  EXPECT_EQ(health.detail, "ok");
  EXPECT_EQ(health.status, io::DeviceStatus::ok);
  EXPECT_EQ(health.reconnects, 0U);
}

TEST_F(ModbusTcp, GarbageAnswersNeverBecomeValues) {
  ModbusServerOptions o = options();
  o.garbage = true;
  ModbusServer server(o);
  auto driver = make_driver(server.port());
  driver->start();
  const auto tally = capture_.run(*driver, 1.0);
  EXPECT_EQ(tally.fresh, 0U);
  EXPECT_EQ(tally.gaps, tally.ticks);
  EXPECT_EQ(tally.mismatches, 0U);
  const auto health = driver->health();
  EXPECT_GT(health.errors, 0U);
  EXPECT_NE(health.detail, "ok");
  EXPECT_NE(health.status, io::DeviceStatus::ok);
}

TEST_F(ModbusTcp, NobodyListeningBacksOffAndReportsDisconnected) {
  int port = 0;
  {
    ModbusServer server(options());  // find a port, then leave it closed
    port = server.port();
  }
  auto driver = make_driver(port, "retries: 0\n");
  driver->start();
  const auto tally = capture_.run(*driver, 1.0);
  EXPECT_EQ(tally.fresh, 0U);
  const auto health = driver->health();
  EXPECT_EQ(health.detail, "disconnected");
  EXPECT_EQ(health.status, io::DeviceStatus::failure);
  EXPECT_GE(health.errors, 1U);
  // Backoff 50, 100, 200, 400, 500 ms...: a handful of attempts a second, not hundreds.
  EXPECT_LE(health.errors, 12U);
  EXPECT_EQ(health.stale_values, tally.ticks * 7);
}

}  // namespace
}  // namespace leakmon::test
