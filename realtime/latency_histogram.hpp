// Wake-up (or sample-to-event) latencies in 1 us bins up to 20 ms, plus min, max, sum and an
// overflow count. One writer records with relaxed atomic increments (no allocation, no lock:
// safe on the real-time thread); any thread may read a consistent-enough snapshot for metrics
// and benchmarks (percentiles from the bins, Prometheus buckets by summing bins).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace leakmon::realtime {

class LatencyHistogram {
 public:
  static constexpr std::size_t kBins = 20000;  // 1 us each

  void record(std::int64_t ns) noexcept {
    if (ns < 0) ns = 0;
    const auto us = static_cast<std::size_t>(ns / 1000);
    if (us < kBins) {
      bins_[us].fetch_add(1, std::memory_order_relaxed);
    } else {
      overflow_.fetch_add(1, std::memory_order_relaxed);
    }
    count_.fetch_add(1, std::memory_order_relaxed);
    sum_ns_.fetch_add(ns, std::memory_order_relaxed);
    if (ns < min_ns_.load(std::memory_order_relaxed)) min_ns_.store(ns, std::memory_order_relaxed);
    if (ns > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(ns, std::memory_order_relaxed);
  }

  std::uint64_t count() const noexcept { return count_.load(std::memory_order_relaxed); }
  std::int64_t sum_ns() const noexcept { return sum_ns_.load(std::memory_order_relaxed); }
  std::int64_t min_ns() const noexcept {
    return count() == 0 ? 0 : min_ns_.load(std::memory_order_relaxed);
  }
  std::int64_t max_ns() const noexcept { return max_ns_.load(std::memory_order_relaxed); }
  double mean_ns() const noexcept {
    const auto n = count();
    return n == 0 ? 0.0 : static_cast<double>(sum_ns()) / static_cast<double>(n);
  }

  // Number of recordings below `ns` (bin resolution: 1 us).
  std::uint64_t count_below(std::int64_t ns) const noexcept {
    const auto limit = std::min<std::size_t>(
        static_cast<std::size_t>(std::max<std::int64_t>(ns, 0) / 1000), kBins);
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < limit; ++i) total += bins_[i].load(std::memory_order_relaxed);
    return total;
  }

  // The q-quantile (0..1) as the upper edge of its 1 us bin; max_ns() when it lies beyond.
  std::int64_t quantile_ns(double q) const noexcept {
    const auto n = count();
    if (n == 0) return 0;
    const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(n - 1)) + 1;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBins; ++i) {
      seen += bins_[i].load(std::memory_order_relaxed);
      if (seen >= rank)
        return std::min<std::int64_t>(static_cast<std::int64_t>(i + 1) * 1000, max_ns());
    }
    return max_ns();
  }

 private:
  std::array<std::atomic<std::uint64_t>, kBins> bins_{};
  std::atomic<std::uint64_t> overflow_{0};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> sum_ns_{0};
  std::atomic<std::int64_t> min_ns_{std::numeric_limits<std::int64_t>::max()};
  std::atomic<std::int64_t> max_ns_{0};
};

}  // namespace leakmon::realtime
