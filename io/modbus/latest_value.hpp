// The handoff from a poller thread to the real-time loop: one writer publishes the values of a
// response with the CLOCK_MONOTONIC time it arrived; the reader takes a consistent snapshot of
// all channels without a lock or an allocation. Values that arrived in one response are read
// together or not at all: per-channel handoffs could pair a new p1 with the previous poll's p2.
//
// A sequence lock: the writer makes the counter odd, stores, makes it even again; a reader that
// saw an odd counter, or a different counter after reading, raced a write and tries again.
// Payload fields are atomics so the race itself is defined (and ThreadSanitizer sees no data
// race); they are stored with release and loaded with acquire ordering instead of relaxed
// accesses between fences (H.-J. Boehm, "Can seqlocks get along with programming language
// memory models?", 2012), which costs nothing on x86 and which GCC's ThreadSanitizer can check
// (it does not support atomic_thread_fence).
//
// The reader never waits on the writer: a write is a few stores, so a retry almost always
// succeeds, and after kMaxAttempts the read gives up and reports "no values" (gaps), which is
// what the loop would do with a late value anyway.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

namespace leakmon::io::modbus {

struct StampedValue {
  double value = 0.0;
  std::int64_t received_ns = 0;  // CLOCK_MONOTONIC; 0: nothing received yet
};

class LatestValues {
 public:
  static constexpr int kMaxAttempts = 8;

  explicit LatestValues(std::size_t channels)
      : size_(channels), slots_(std::make_unique<Slot[]>(channels)) {}

  std::size_t size() const { return size_; }

  // Single writer: begin_write(), set() the channels of one response, end_write().
  void begin_write() {
    const std::uint64_t seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);
  }
  void set(std::size_t channel, double value, std::int64_t received_ns) {
    // Release: a reader that sees a new field also sees the odd counter stored before it.
    slots_[channel].value.store(value, std::memory_order_release);
    slots_[channel].received_ns.store(received_ns, std::memory_order_release);
  }
  void end_write() {
    sequence_.store(sequence_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  // Fills `out` (size() entries) with one consistent snapshot; false when every attempt raced
  // a write (out is then unspecified).
  bool read(std::span<StampedValue> out) const {
    for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
      const std::uint64_t before = sequence_.load(std::memory_order_acquire);
      if (before % 2 != 0) continue;
      for (std::size_t i = 0; i < size_; ++i) {
        // Acquire: having read a new field, the re-read counter cannot be the old one.
        out[i].value = slots_[i].value.load(std::memory_order_acquire);
        out[i].received_ns = slots_[i].received_ns.load(std::memory_order_acquire);
      }
      if (sequence_.load(std::memory_order_relaxed) == before) return true;
    }
    return false;
  }

 private:
  struct Slot {
    std::atomic<double> value{0.0};
    std::atomic<std::int64_t> received_ns{0};
  };

  std::size_t size_;
  std::unique_ptr<Slot[]> slots_;
  alignas(64) std::atomic<std::uint64_t> sequence_{0};
};

}  // namespace leakmon::io::modbus
