// Hand-over of the newest values from a slow driver's poller thread (a Modbus read can take
// several ms) to the real-time read(): a triple buffer. The poller fills its private slot and
// swaps it with the shared middle slot; the reader swaps the middle slot into its own when it
// is newer. Neither side ever waits for the other, and each slot is touched by one thread at a
// time, so the values themselves need no atomics. The reader learns how old its values are and
// turns values older than `max_age` into gaps (DriverHealth::stale_values).
#pragma once

#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace leakmon::io {

class PolledValues {
 public:
  explicit PolledValues(std::size_t channels) {
    for (auto& slot : slots_) slot.values.assign(channels, std::numeric_limits<double>::quiet_NaN());
  }
  PolledValues(const PolledValues&) = delete;
  PolledValues& operator=(const PolledValues&) = delete;

  std::size_t channels() const { return slots_[0].values.size(); }

  // Poller thread: publish one complete set of values measured at `monotonic_ns`.
  void publish(std::span<const double> values, std::int64_t monotonic_ns) noexcept {
    Slot& slot = slots_[write_index_];
    for (std::size_t i = 0; i < slot.values.size() && i < values.size(); ++i) {
      slot.values[i] = values[i];
    }
    slot.monotonic_ns = monotonic_ns;
    // release: the slot's contents happen-before the reader's acquire of the swapped index.
    const unsigned previous = middle_.exchange(write_index_ | kFresh, std::memory_order_acq_rel);
    write_index_ = previous & kIndexMask;
  }

  // Real-time thread: copy the newest values into `out`. Returns their age in ns at `now_ns`,
  // or -1 when nothing was ever published (then `out` is all NaN). Values older than
  // `max_age_ns` are replaced by NaN (the age is still returned). Never blocks or allocates.
  std::int64_t latest(std::span<double> out, std::int64_t now_ns,
                      std::int64_t max_age_ns) noexcept {
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      const unsigned previous = middle_.exchange(read_index_, std::memory_order_acq_rel);
      read_index_ = previous & kIndexMask;
    }
    const Slot& slot = slots_[read_index_];
    const bool never = slot.monotonic_ns == kNever;
    const std::int64_t age = never ? -1 : now_ns - slot.monotonic_ns;
    const bool stale = never || age > max_age_ns;
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = (stale || i >= slot.values.size()) ? std::numeric_limits<double>::quiet_NaN()
                                                  : slot.values[i];
    }
    return age;
  }

 private:
  static constexpr unsigned kFresh = 4;
  static constexpr unsigned kIndexMask = 3;
  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();

  struct Slot {
    std::vector<double> values;
    std::int64_t monotonic_ns = kNever;
  };

  std::array<Slot, 3> slots_;
  unsigned write_index_ = 0;                // owned by the poller
  unsigned read_index_ = 1;                 // owned by the reader
  std::atomic<unsigned> middle_{2};         // shared: index of the middle slot | kFresh
};

}  // namespace leakmon::io
