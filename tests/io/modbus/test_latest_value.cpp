#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

#include "io/modbus/latest_value.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::io::modbus {
namespace {

TEST(LatestValue, EmptyUntilPublished) {
  LatestValue slot;
  EXPECT_FALSE(slot.read().has_value());
  slot.publish(2.5, 17);
  const auto sample = slot.read();
  ASSERT_TRUE(sample.has_value());
  EXPECT_EQ(sample->value, 2.5);
  EXPECT_EQ(sample->received_ns, 17);
}

TEST(LatestValue, ReadAllocatesNothing) {
  LatestValue slot;
  slot.publish(1.0, 1);
  test::AllocationScope scope;
  double sum = 0.0;
  for (int i = 0; i < 1000; ++i) sum += slot.read()->value;
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(sum, 1000.0);
}

// The writer publishes pairs whose value and time belong together (value == time / 2); a
// reader racing it must never see one pair's value with another pair's time, and must see time
// move forward only.
TEST(LatestValue, ReaderNeverSeesATornPairUnderContention) {
  LatestValue slot;
  std::atomic<bool> reader_done{false};
  std::thread writer([&] {
    for (std::int64_t i = 1; !reader_done.load(std::memory_order_acquire); ++i)
      slot.publish(static_cast<double>(i) / 2.0, i);
  });
  std::int64_t last_seen = 0;
  std::uint64_t seen = 0;
  std::uint64_t torn = 0;
  std::uint64_t went_back = 0;
  for (int read = 0; read < 200'000; ++read) {
    const auto sample = slot.read();
    if (!sample) continue;
    if (sample->value != static_cast<double>(sample->received_ns) / 2.0) ++torn;
    if (sample->received_ns < last_seen) ++went_back;
    last_seen = sample->received_ns;
    ++seen;
  }
  reader_done.store(true, std::memory_order_release);
  writer.join();
  EXPECT_EQ(torn, 0U);
  EXPECT_EQ(went_back, 0U);
  EXPECT_GT(seen, 0U);
  EXPECT_GT(last_seen, 1);  // the reader saw the writer make progress
}

}  // namespace
}  // namespace leakmon::io::modbus
