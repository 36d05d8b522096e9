#include "views/snapshot.hpp"

#include <cmath>

namespace leakmon::views {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

double LatencySummary::mean_us() const {
  return count == 0 ? kNaN : static_cast<double>(sum_ns) / static_cast<double>(count) / 1e3;
}

double LatencySummary::max_us() const {
  return count == 0 ? kNaN : static_cast<double>(max_ns) / 1e3;
}

double LatencySummary::p99_us() const {
  return count == 0 ? kNaN : static_cast<double>(p99_ns) / 1e3;
}

void summarize(const realtime::LatencyHistogram& histogram, LatencySummary& out) {
  out.count = histogram.count();
  out.sum_ns = histogram.sum_ns();
  out.max_ns = histogram.max_ns();
  out.p99_ns = histogram.quantile_ns(0.99);
  for (std::size_t i = 0; i < kLatencyBucketsSeconds.size(); ++i) {
    out.below[i] = histogram.count_below(
        static_cast<std::int64_t>(std::llround(kLatencyBucketsSeconds[i] * 1e9)));
  }
}

void read_group(GroupSnapshot& out, const std::string& name, const realtime::LoopCounters& counters,
                std::size_t ring_capacity, bool realtime, std::int64_t now_ns) {
  out.name = name;
  out.realtime = realtime;
  out.ended = counters.end_of_stream.load(std::memory_order_relaxed);
  out.cycles = counters.cycles.load(std::memory_order_relaxed);
  out.overruns = counters.overruns.load(std::memory_order_relaxed);
  out.missed_cycles = counters.missed_cycles.load(std::memory_order_relaxed);
  out.ring_drops = counters.ring_drops.load(std::memory_order_relaxed);
  out.ring_high_water = counters.ring_high_water.load(std::memory_order_relaxed);
  out.ring_capacity = ring_capacity;
  const std::int64_t last = counters.last_cycle_ns.load(std::memory_order_relaxed);
  out.last_cycle_age_s = last == 0 ? kNaN : static_cast<double>(now_ns - last) / 1e9;
  summarize(counters.wakeup_latency, out.wakeup_latency);
}

}  // namespace leakmon::views
