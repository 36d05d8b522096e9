// health() is read by the daemon's metrics thread while the real-time thread calls read():
// run both at once so ThreadSanitizer (this test is in the TSan build) sees every shared field.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/canlog/canlog_driver.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::io {
namespace {

TEST(CanlogHealthThreads, HealthIsSafeToReadWhileReplaying) {
  const std::string dir = test::scratch_dir("canlog_health_threads");
  {
    std::ofstream log(dir + "/bus.log");
    for (int k = 0; k < 3000; ++k) {
      char line[96];
      std::snprintf(line, sizeof line, "(%d.%06d) can0 101#%02X\n(%d.%06d) can0 20000040#00\n",
                    k / 500, (k % 500) * 2000, k % 256, k / 500, (k % 500) * 2000 + 1);
      log << line;  // a one-byte frame (too short) and a bus-off error frame every sample
    }
  }
  std::ofstream(dir + "/replay.yaml") << "name: replay\ntype: canlog\nfile: bus.log\nsignals:\n"
                                         "  - channel: p1\n    id: 0x101\n    length: 16\n";
  auto driver = make_canlog_driver(config::ConfigNode::load_file(dir + "/replay.yaml"));
  driver->start();
  std::atomic<bool> done{false};
  std::uint64_t last_errors = 0;
  std::thread metrics([&] {
    while (!done.load()) {
      const DriverHealth h = driver->health();
      EXPECT_GE(h.errors, last_errors) << "counters never go back";
      last_errors = h.errors;
    }
  });
  std::vector<double> values(1);
  std::uint64_t tick = 0;
  while (driver->read(Tick{tick, static_cast<std::int64_t>(tick) * 2'000'000}, values) ==
         ReadStatus::ok) {
    ++tick;
  }
  done = true;
  metrics.join();
  EXPECT_EQ(driver->health().errors, 6000U) << "3000 error frames and 3000 short frames";
  EXPECT_EQ(driver->health().detail, "bus-off");
  EXPECT_EQ(driver->health().status, DeviceStatus::failure);
}

}  // namespace
}  // namespace leakmon::io
