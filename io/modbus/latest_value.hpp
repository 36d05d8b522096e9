// The handoff from a poller thread to the real-time loop: one writer publishes a value with the
// CLOCK_MONOTONIC time it was received; any reader takes the newest consistent pair without a
// lock or an allocation. A sequence lock: the writer makes the counter odd, stores, makes it
// even again; a reader that saw an odd counter, or a different counter after reading, raced a
// write and tries again. Payload fields are relaxed atomics so the race itself is defined (and
// ThreadSanitizer sees no data race); the fences order them against the counter.
//
// The reader never waits on the writer: a write is two stores, so a retry almost always
// succeeds, and after kMaxAttempts the read gives up and reports "no value" (a gap), which is
// what the loop would do with a late value anyway.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>

namespace leakmon::io::modbus {

struct StampedValue {
  double value = 0.0;
  std::int64_t received_ns = 0;  // CLOCK_MONOTONIC
};

class alignas(64) LatestValue {  // one cache line each: channels do not false-share
 public:
  static constexpr int kMaxAttempts = 8;

  // Single writer only.
  void publish(double value, std::int64_t received_ns) {
    const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    value_.store(value, std::memory_order_relaxed);
    received_ns_.store(received_ns, std::memory_order_relaxed);
    sequence_.store(seq + 2, std::memory_order_release);
  }

  // Nothing yet published, or a write raced every attempt: nullopt.
  std::optional<StampedValue> read() const {
    for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if (before % 2 != 0) continue;
      const StampedValue sample{value_.load(std::memory_order_relaxed),
                                received_ns_.load(std::memory_order_relaxed)};
      std::atomic_thread_fence(std::memory_order_acquire);
      if (sequence_.load(std::memory_order_relaxed) != before) continue;
      if (before == 0) return std::nullopt;
      return sample;
    }
    return std::nullopt;
  }

 private:
  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<double> value_{0.0};
  std::atomic<std::int64_t> received_ns_{0};
};

}  // namespace leakmon::io::modbus
