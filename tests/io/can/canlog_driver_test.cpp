#include "io/canlog/canlog_driver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::io {
namespace {

constexpr std::int64_t kMs = 1'000'000;

std::string write_file(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::unique_ptr<Driver> replay(const std::string& dir, const std::string& log,
                               const std::string& extra = "") {
  write_file(dir, "bus.log", log);
  const std::string yaml =
      "name: replay\ntype: canlog\nfile: bus.log\n" + extra +
      "signals:\n"
      "  - channel: p1\n    id: 0x101\n    length: 16\n    factor: 500\n"
      "  - channel: x\n    id: 0x102\n    start_bit: 7\n    length: 16\n"
      "    byte_order: motorola\n    signed: true\n    factor: 1.0e-5\n    max_age: 0.005\n";
  return make_canlog_driver(config::ConfigNode::load_file(write_file(dir, "replay.yaml", yaml)));
}

TEST(CanlogDriver, ReplaysOnTheTickClockWithGapsForSilentSignals) {
  const std::string dir = test::scratch_dir("canlog_tick_clock");
  // p1 every 2 ms; x only at the start, so it goes stale after its 5 ms max age.
  auto driver = replay(dir,
                       "(100.000000) can0 101#E803\n"    // p1 = 1000 * 500 Pa
                       "(100.000100) can0 102#FF38\n"    // x = -200 * 1e-5 m
                       "(100.002000) can0 101#D007\n"    // 2000
                       "(100.004000) can0 101#B80B\n"    // 3000
                       "(100.006000) can0 101#A00F\n"    // 4000
                       "(100.008000) can0 101#8813\n");  // 5000
  driver->start();
  std::vector<double> v(2);
  const std::int64_t t0 = 5'000 * kMs;  // the loop's clock has its own origin
  ASSERT_EQ(driver->read(Tick{0, t0}, v), ReadStatus::ok);
  EXPECT_EQ(v[0], 500'000.0);
  EXPECT_TRUE(std::isnan(v[1])) << "x arrives 0.1 ms after the first tick";
  ASSERT_EQ(driver->read(Tick{1, t0 + 2 * kMs}, v), ReadStatus::ok);
  EXPECT_EQ(v[0], 1'000'000.0);
  EXPECT_DOUBLE_EQ(v[1], -0.002);
  EXPECT_DOUBLE_EQ(*driver->source_time(), 100.002);
  // A missed cycle: tick 2 never happened; tick 3 sees the frame of t = 6 ms.
  ASSERT_EQ(driver->read(Tick{3, t0 + 6 * kMs}, v), ReadStatus::ok);
  EXPECT_EQ(v[0], 2'000'000.0);
  EXPECT_TRUE(std::isnan(v[1])) << "5.9 ms old, max age 5 ms";
  EXPECT_EQ(driver->health().stale_values, 1U);
  ASSERT_EQ(driver->read(Tick{4, t0 + 8 * kMs}, v), ReadStatus::ok);
  EXPECT_EQ(v[0], 2'500'000.0);
  EXPECT_EQ(driver->read(Tick{5, t0 + 10 * kMs}, v), ReadStatus::end_of_stream);
}

TEST(CanlogDriver, FastPaceAdvancesOnePeriodPerRead) {
  const std::string dir = test::scratch_dir("canlog_fast");
  auto driver = replay(dir,
                       "(100.000000) can0 101#0100\n"
                       "(100.010000) can0 101#0200\n"
                       "(100.020000) can0 101#0300\n",
                       "pace: fast\nperiod: 0.01\nmax_age: 0.05\n");
  driver->start();
  std::vector<double> v(2);
  std::vector<double> p1;
  // The tick clock stands still: only the number of reads matters.
  while (driver->read(Tick{0, 0}, v) == ReadStatus::ok) p1.push_back(v[0]);
  EXPECT_EQ(p1, (std::vector<double>{500.0, 1000.0, 1500.0}));
}

TEST(CanlogDriver, ErrorFramesChangeHealthNotValues) {
  const std::string dir = test::scratch_dir("canlog_errors");
  auto driver = replay(dir,
                       "(1.000) can0 101#0100\n"
                       "(1.001) can0 20000040#0000000000000000\n"  // bus-off
                       "(1.002) can0 101#0200\n"
                       "(1.003) can0 20000100#0000000000000000\n"  // restarted
                       "(1.004) can0 101#03\n");                   // too short for 16 bits
  driver->start();
  std::vector<double> v(2);
  driver->read(Tick{0, 0}, v);
  EXPECT_EQ(driver->health().detail, "ok");
  EXPECT_EQ(driver->health().status, DeviceStatus::ok);
  driver->read(Tick{1, 1 * kMs + 500'000}, v);
  EXPECT_EQ(driver->health().detail, "bus-off");
  EXPECT_EQ(driver->health().status, DeviceStatus::failure);
  EXPECT_EQ(driver->health().last_error, "bus-off");
  EXPECT_EQ(v[0], 500.0);
  driver->read(Tick{2, 3 * kMs + 500'000}, v);
  EXPECT_EQ(driver->health().detail, "ok");
  EXPECT_EQ(driver->health().status, DeviceStatus::ok);
  EXPECT_EQ(v[0], 1000.0);
  driver->read(Tick{3, 4 * kMs + 500'000}, v);
  EXPECT_EQ(v[0], 1000.0) << "a short frame keeps the last good value";
  EXPECT_EQ(driver->health().errors, 3U) << "two error frames and one short frame";
}

TEST(CanlogDriver, MalformedLogFailsAtStartWithFileLineColumn) {
  const std::string dir = test::scratch_dir("canlog_malformed");
  auto driver = replay(dir, "(1.000) can0 101#0100\n(1.002) can0 101#01000\n");
  try {
    driver->start();
    FAIL() << "no error";
  } catch (const DriverError& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/bus.log:2:23: odd number of hex digits in the data");
  }
}

TEST(CanlogDriver, ReadAllocatesNothing) {
  const std::string dir = test::scratch_dir("canlog_alloc");
  std::string log;
  for (int k = 0; k < 2000; ++k) {
    char line[64];
    std::snprintf(line, sizeof line, "(10.%06d) can0 101#%02X00\n(10.%06d) can0 102#0010\n",
                  k * 400, k % 256, k * 400 + 1);
    log += line;
  }
  auto driver = replay(dir, log);
  driver->start();
  std::vector<double> v(2);
  std::uint64_t ticks = 0;
  test::AllocationScope scope;
  while (driver->read(Tick{ticks, static_cast<std::int64_t>(ticks) * 2 * kMs}, v) ==
         ReadStatus::ok) {
    ++ticks;
  }
  EXPECT_EQ(scope.count(), 0U);
  // 0.8 s of log at 2 ms per tick; the last frames (at 799.6 ms) arrive with tick 400.
  EXPECT_EQ(ticks, 401U);
}

}  // namespace
}  // namespace leakmon::io
