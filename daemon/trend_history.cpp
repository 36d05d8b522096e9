#include "daemon/trend_history.hpp"
#include "capture/units.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace leakmon::daemon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TrendPoint point_of(double unix_time, const ActuatorStatus& a) {
  TrendPoint p;
  p.unix_time = unix_time;
  p.index_p1 = a.index_p1;
  p.index_p2 = a.index_p2;
  p.score = a.score;
  p.raise_threshold = a.raise_threshold;
  p.leak_lpm_per_mpa = units::lpm_per_mpa(a.leak_coefficient);
  p.leak_lpm_per_mpa_ci95 = units::lpm_per_mpa(a.leak_coefficient_ci);
  p.p1 = a.p1;
  p.p2 = a.p2;
  p.oil_temperature = a.oil_temperature;
  p.alarm = static_cast<std::uint8_t>(a.state);
  p.learning = a.learning;
  p.suspended = a.suspended;
  p.channel_status.fill(TrendPoint::kNoChannel);
  for (std::size_t i = 0; i < std::min(a.channels.size(), p.channel_status.size()); ++i) {
    p.channel_status[i] = static_cast<std::uint8_t>(a.channels[i].status);
  }
  return p;
}

}  // namespace

void read_loop_health(LoopHealth& out, const std::string& group, const LoopCounters& counters,
                      std::size_t ring_capacity, bool realtime) {
  out.group = group;
  out.realtime = realtime;
  out.cycles = counters.cycles.load(std::memory_order_relaxed);
  out.overruns = counters.overruns.load(std::memory_order_relaxed);
  out.missed_cycles = counters.missed_cycles.load(std::memory_order_relaxed);
  out.ring_drops = counters.ring_drops.load(std::memory_order_relaxed);
  out.ring_high_water = counters.ring_high_water.load(std::memory_order_relaxed);
  out.ring_capacity = ring_capacity;
  out.latency_count = counters.wakeup_latency.count();
  out.latency_sum_ns = counters.wakeup_latency.sum_ns();
  out.latency_max_ns = counters.wakeup_latency.max_ns();
  out.latency_p99_ns = counters.wakeup_latency.quantile_ns(0.99);
}

std::size_t trend_capacity(double seconds, double interval_s) {
  return std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(seconds / interval_s)));
}

TrendHistory::TrendHistory(std::size_t capacity, const std::vector<std::string>& actuators,
                           const std::vector<std::string>& groups)
    : capacity_(std::max<std::size_t>(capacity, 2)) {
  actuators_.reserve(actuators.size());
  for (const auto& name : actuators) actuators_.push_back({name, FixedRing<TrendPoint>(capacity_)});
  groups_.reserve(groups.size());
  for (const auto& name : groups) groups_.push_back({name, FixedRing<LoopPoint>(capacity_)});
}

const TrendHistory::ActuatorSeries* TrendHistory::actuator(const std::string& name) const {
  for (const auto& series : actuators_) {
    if (series.name == name) return &series;
  }
  return nullptr;
}

const TrendHistory::GroupSeries* TrendHistory::group(const std::string& name) const {
  for (const auto& series : groups_) {
    if (series.name == name) return &series;
  }
  return nullptr;
}

void TrendHistory::record(double unix_time, const ViewSnapshot& snapshot) {
  for (const auto& status : snapshot.actuators) {
    auto it = std::find_if(actuators_.begin(), actuators_.end(),
                           [&](const ActuatorSeries& s) { return s.name == status.name; });
    if (it == actuators_.end()) {
      actuators_.push_back({status.name, FixedRing<TrendPoint>(capacity_)});
      it = actuators_.end() - 1;
    }
    it->points.push(point_of(unix_time, status));
  }
  for (const auto& health : snapshot.groups) {
    auto it = std::find_if(groups_.begin(), groups_.end(),
                           [&](const GroupSeries& s) { return s.name == health.group; });
    if (it == groups_.end()) {
      groups_.push_back({health.group, FixedRing<LoopPoint>(capacity_)});
      it = groups_.end() - 1;
      it->last_count = health.latency_count;
      it->last_sum_ns = health.latency_sum_ns;
    }
    LoopPoint p;
    p.unix_time = unix_time;
    const std::uint64_t cycles = health.latency_count - it->last_count;
    p.latency_mean_us = cycles == 0 ? kNaN
                                    : static_cast<double>(health.latency_sum_ns - it->last_sum_ns) /
                                          static_cast<double>(cycles) / 1e3;
    p.overruns = health.overruns;
    p.ring_drops = health.ring_drops;
    it->points.push(p);
    it->last_count = health.latency_count;
    it->last_sum_ns = health.latency_sum_ns;
  }
}

std::size_t TrendHistory::memory_bytes(std::size_t capacity, std::size_t actuators,
                                       std::size_t groups) {
  return capacity * (actuators * sizeof(TrendPoint) + groups * sizeof(LoopPoint));
}

std::size_t TrendHistory::memory_bytes() const {
  return memory_bytes(capacity_, actuators_.size(), groups_.size());
}

}  // namespace leakmon::daemon
