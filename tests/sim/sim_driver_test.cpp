// The daemon's sim driver passes the scenario's drifting conditions, sensor faults and optional
// transducers through: ps and temp are channels when the scenario records them (or when named),
// and a dropped-out channel reads NaN (a gap) on the real-time path.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "io/sim/sim_driver.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::io {
namespace {

TEST(SimDriverChannels, RecordedTransducersAndFaultsReachTheDriver) {
  SimSettings settings;
  settings.scenario = sim::preset("healthy", 2);
  sim::TemperatureProfile hot;
  hot.T_work = 52.0;
  settings.scenario.conditions.temperature = hot;
  settings.scenario.record.temp = true;
  sim::SensorFault gap{sim::SensorFault::Kind::dropout, sim::SensorChannel::p2, 0.1, 0.1};
  gap.gap = true;
  settings.scenario.faults = {gap};
  SimDriver driver(settings);
  EXPECT_EQ(std::vector<std::string>(driver.channels().begin(), driver.channels().end()),
            (std::vector<std::string>{"xref", "u", "x", "p1", "p2", "q_int", "temp"}));
  driver.start();
  std::vector<double> values(driver.channels().size());
  int gaps = 0;
  {
    test::AllocationScope scope;
    for (std::uint64_t k = 0; k < 200; ++k) {
      ASSERT_EQ(driver.read(Tick{k, 0}, values), ReadStatus::ok);
      EXPECT_NEAR(values[6], 52.0, 0.3);
      gaps += std::isnan(values[4]);
      EXPECT_FALSE(std::isnan(values[3]));
    }
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_EQ(gaps, 50);  // 0.1 s at 500 Hz

  settings.channels = {"p1", "ps"};
  SimDriver named(settings);
  named.start();
  std::vector<double> two(2);
  ASSERT_EQ(named.read(Tick{0, 0}, two), ReadStatus::ok);
  EXPECT_NEAR(two[1], 17.2e6, 3e4);
  settings.channels = {"flow"};
  EXPECT_THROW(SimDriver{settings}, DriverError);
}

// A real rig does not pause while the daemon misses cycles: the simulated one steps through the
// missed ticks, so its time stays the tick's time (before, a loaded machine delayed a leak set to
// open at 40 s by every missed cycle, and the daemon's samples around a gap joined without one).
TEST(SimDriverTime, TheRigKeepsRunningThroughMissedTicks) {
  SimSettings settings;
  settings.scenario = sim::preset("healthy", 3);
  SimDriver driver(settings);
  driver.start();
  std::vector<double> values(driver.channels().size());
  constexpr double kPeriod = 0.002;
  test::AllocationScope scope;
  for (std::uint64_t k = 0; k < 10; ++k) ASSERT_EQ(driver.read(Tick{k, 0}, values), ReadStatus::ok);
  EXPECT_NEAR(*driver.source_time(), 9 * kPeriod, 1e-9);
  ASSERT_EQ(driver.read(Tick{60, 0}, values), ReadStatus::ok);  // 50 ticks missed
  EXPECT_NEAR(*driver.source_time(), 60 * kPeriod, 1e-9);
  // A stall of 1000 ticks is made up at most kSimMaxCatchUpSteps per read.
  ASSERT_EQ(driver.read(Tick{1061, 0}, values), ReadStatus::ok);
  EXPECT_NEAR(*driver.source_time(), (61 + kSimMaxCatchUpSteps) * kPeriod, 1e-9);
  std::uint64_t tick = 1062;
  for (; tick < 1200; ++tick) ASSERT_EQ(driver.read(Tick{tick, 0}, values), ReadStatus::ok);
  EXPECT_NEAR(*driver.source_time(), 1199 * kPeriod, 1e-9);
  EXPECT_EQ(scope.count(), 0u);
}

}  // namespace
}  // namespace leakmon::io
