// The live page's memory: the last hours of every actuator's trend (index, score against its
// threshold, leak size with its 95 % interval, chamber pressures, oil temperature, alarm and
// sensor states) and of every sampling group's loop health, at a fixed interval, in rings
// allocated once when the daemon starts. Recording a point allocates nothing, so the sampler
// (a plain thread, never the real-time loops) costs a copy of a few hundred bytes a second.
// Not synchronised: OperatorView (operator_view.hpp) guards it with its mutex.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "views/snapshot.hpp"

namespace leakmon::views {

// One actuator at one instant. Leak sizes in l/min/MPa (at 40 degC when the oil temperature is
// acquired), pressures and the index in Pa.
struct TrendPoint {
  double unix_time = 0.0;
  double index_p1 = 0.0, index_p2 = 0.0;
  double score = 0.0, raise_threshold = 0.0;
  double leak_lpm_per_mpa = 0.0, leak_lpm_per_mpa_ci95 = 0.0;
  double p1 = 0.0, p2 = 0.0;
  double oil_temperature = 0.0;
  std::uint8_t alarm = 0;  // pipeline::AlarmState
  bool learning = false;
  bool suspended = false;
  // io::DeviceStatus of the checked channels (p1, p2, x, in ActuatorStatus::channels order);
  // kNoChannel where the actuator has fewer.
  std::array<std::uint8_t, 3> channel_status{};
  static constexpr std::uint8_t kNoChannel = 255;
};

// One sampling group over one interval.
struct LoopPoint {
  double unix_time = 0.0;
  double latency_mean_us = 0.0;  // mean wake-up latency over the interval (NaN: no cycle)
  std::uint64_t overruns = 0;    // in total since the start
  std::uint64_t ring_drops = 0;
};

// A ring of `capacity` values allocated at construction; push() overwrites the oldest.
template <typename T>
class FixedRing {
 public:
  explicit FixedRing(std::size_t capacity) : values_(capacity) {}
  void push(const T& value) {
    values_[next_] = value;
    next_ = (next_ + 1) % values_.size();
    if (size_ < values_.size()) ++size_;
  }
  std::size_t size() const { return size_; }
  std::size_t capacity() const { return values_.size(); }
  // The i-th oldest value, 0 <= i < size().
  const T& operator[](std::size_t i) const {
    return values_[(next_ + values_.size() - size_ + i) % values_.size()];
  }

 private:
  std::vector<T> values_;
  std::size_t next_ = 0;
  std::size_t size_ = 0;
};

class TrendHistory {
 public:
  // Rings of `capacity` points for each named actuator and group, allocated now.
  TrendHistory(std::size_t capacity, const std::vector<std::string>& actuators,
               const std::vector<std::string>& groups);

  // Appends one point per actuator and group of `snapshot`. Allocates nothing for the names
  // given at construction; an actuator added by a reload gets its ring here, once.
  void record(double unix_time, const ServiceSnapshot& snapshot);

  struct ActuatorSeries {
    std::string name;
    FixedRing<TrendPoint> points;
  };
  struct GroupSeries {
    std::string name;
    FixedRing<LoopPoint> points;
    std::uint64_t last_count = 0;  // latency histogram totals at the previous point
    std::int64_t last_sum_ns = 0;
  };
  const std::vector<ActuatorSeries>& actuators() const { return actuators_; }
  const std::vector<GroupSeries>& groups() const { return groups_; }
  // The series of `name`, or nullptr.
  const ActuatorSeries* actuator(const std::string& name) const;
  const GroupSeries* group(const std::string& name) const;

  // Points of `actuator` kept from before a restart (decode_trend), oldest first: the newest
  // `capacity` of them go into its ring ahead of anything recorded since. False when the
  // configuration has no such actuator any more.
  bool restore(const std::string& actuator, const std::vector<TrendPoint>& points);

  std::size_t capacity() const { return capacity_; }
  // The bytes the rings hold: capacity x (sizeof(TrendPoint) per actuator + sizeof(LoopPoint)
  // per group). What docs/daemon.md states.
  std::size_t memory_bytes() const;
  static std::size_t memory_bytes(std::size_t capacity, std::size_t actuators, std::size_t groups);

 private:
  std::size_t capacity_;
  std::vector<ActuatorSeries> actuators_;
  std::vector<GroupSeries> groups_;
};

// An actuator's trend as text, to survive a restart: a versioned first line, a header, then one
// CSV row a point (NaN as "nan"). decode_trend() throws std::runtime_error naming the line and
// the field of the first thing that is wrong (a newer version, a short row, a bad number).
std::string encode_trend(const FixedRing<TrendPoint>& points);
std::vector<TrendPoint> decode_trend(std::string_view text);

// Trend points kept for `seconds` of history at one point every `interval_s` (at least 2).
std::size_t trend_capacity(double seconds, double interval_s);

}  // namespace leakmon::views
