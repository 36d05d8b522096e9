#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include "io/modbus/latest_value.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::io::modbus {
namespace {

TEST(LatestValues, NothingReceivedUntilWritten) {
  LatestValues values(2);
  std::array<StampedValue, 2> out{};
  ASSERT_TRUE(values.read(out));
  EXPECT_EQ(out[0].received_ns, 0);
  values.begin_write();
  values.set(1, 2.5, 17);
  values.end_write();
  ASSERT_TRUE(values.read(out));
  EXPECT_EQ(out[0].received_ns, 0);  // channel 0 was not part of that response
  EXPECT_EQ(out[1].value, 2.5);
  EXPECT_EQ(out[1].received_ns, 17);
}

TEST(LatestValues, ReadAllocatesNothing) {
  LatestValues values(3);
  values.begin_write();
  values.set(0, 1.0, 1);
  values.end_write();
  std::array<StampedValue, 3> out{};
  test::AllocationScope scope;
  double sum = 0.0;
  for (int i = 0; i < 1000; ++i) {
    values.read(out);
    sum += out[0].value;
  }
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(sum, 1000.0);
}

// The writer publishes responses whose channels belong together (b == 2 a, both stamped i); a
// reader racing it must never see channels of different responses mixed, nor a value with
// another response's time, and must see time move forward only.
TEST(LatestValues, ReaderNeverSeesATornSnapshotUnderContention) {
  LatestValues values(2);
  std::atomic<bool> reader_done{false};
  std::atomic<bool> writer_started{false};
  std::thread writer([&] {
    for (std::int64_t i = 1; !reader_done.load(std::memory_order_acquire); ++i) {
      values.begin_write();
      values.set(0, static_cast<double>(i), i);
      values.set(1, 2.0 * static_cast<double>(i), i);
      values.end_write();
      writer_started.store(true, std::memory_order_release);
      // The poller writes once per response, not back to back: leave the reader a window
      // (busy, so that the writer stays on its core and the two keep racing).
      const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(2);
      while (std::chrono::steady_clock::now() < until) {
      }
    }
  });
  while (!writer_started.load(std::memory_order_acquire)) std::this_thread::yield();
  std::array<StampedValue, 2> out{};
  std::int64_t last_seen = 0;
  std::uint64_t seen = 0;
  std::uint64_t torn = 0;
  std::uint64_t went_back = 0;

  // Reads until enough consistent snapshots were seen: a writer preempted inside its write
  // (sanitizer builds, a loaded machine) makes every read in between fail, as it must. The
  // deadline only bounds the test; nothing is asserted about time.
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (seen < 20'000 && std::chrono::steady_clock::now() < give_up) {
    if (!values.read(out)) continue;
    if (out[0].received_ns != out[1].received_ns || out[1].value != 2.0 * out[0].value ||
        out[0].value != static_cast<double>(out[0].received_ns))
      ++torn;
    if (out[0].received_ns < last_seen) ++went_back;
    last_seen = out[0].received_ns;
    ++seen;
  }
  reader_done.store(true, std::memory_order_release);
  writer.join();
  EXPECT_EQ(torn, 0U);
  EXPECT_EQ(went_back, 0U);
  EXPECT_GT(seen, 0U);
}

}  // namespace
}  // namespace leakmon::io::modbus
