#include "views/trend_history.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <stdexcept>

#include "capture/units.hpp"

namespace leakmon::views {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TrendPoint point_of(double unix_time, const pipeline::ActuatorStatus& a) {
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

constexpr std::string_view kTrendMagic = "# leakmon trend ";
constexpr int kTrendVersion = 1;
// The file's columns, in order: its header line and the fields a bad row's error names.
constexpr std::string_view kTrendColumns[] = {"unix_time",
                                              "index_p1",
                                              "index_p2",
                                              "score",
                                              "raise_threshold",
                                              "leak_lpm_per_mpa",
                                              "leak_lpm_per_mpa_ci95",
                                              "p1",
                                              "p2",
                                              "oil_temperature",
                                              "alarm",
                                              "learning",
                                              "suspended",
                                              "channel_1",
                                              "channel_2",
                                              "channel_3"};
constexpr std::size_t kTrendFields = std::size(kTrendColumns);

std::string trend_header() { return fmt::format("{}", fmt::join(kTrendColumns, ",")); }

double parse_number(std::string_view field, std::size_t line, std::string_view column) {
  const std::string text(field);
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE) {
    throw std::runtime_error(
        fmt::format("line {}, field {}: '{}' is not a number", line, column, text.substr(0, 40)));
  }
  return value;
}

std::uint8_t parse_small(std::string_view field, std::size_t line, std::string_view column,
                         unsigned max) {
  const double value = parse_number(field, line, column);
  if (!(value >= 0.0 && value <= max) || value != std::floor(value)) {
    throw std::runtime_error(
        fmt::format("line {}, field {}: {} is not an integer 0..{}", line, column, value, max));
  }
  return static_cast<std::uint8_t>(value);
}

}  // namespace

std::string encode_trend(const FixedRing<TrendPoint>& points) {
  std::string out = fmt::format("{}{}\n{}\n", kTrendMagic, kTrendVersion, trend_header());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const TrendPoint& p = points[i];
    fmt::format_to(std::back_inserter(out),
                   "{:.3f},{},{},{},{},{},{},{},{},{},{},{},{},{},{},"
                   "{}\n",
                   p.unix_time, p.index_p1, p.index_p2, p.score, p.raise_threshold,
                   p.leak_lpm_per_mpa, p.leak_lpm_per_mpa_ci95, p.p1, p.p2, p.oil_temperature,
                   p.alarm, p.learning ? 1 : 0, p.suspended ? 1 : 0, p.channel_status[0],
                   p.channel_status[1], p.channel_status[2]);
  }
  return out;
}

std::vector<TrendPoint> decode_trend(std::string_view text) {
  std::vector<TrendPoint> points;
  std::size_t line_number = 0;
  std::vector<std::string_view> fields;
  const std::string header = trend_header();
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    const std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    ++line_number;
    if (line_number == 1) {
      if (line.substr(0, kTrendMagic.size()) != kTrendMagic) {
        throw std::runtime_error("line 1: not a leakmon trend file");
      }
      const double version = parse_number(line.substr(kTrendMagic.size()), 1, "version");
      if (version != kTrendVersion) {
        throw std::runtime_error(fmt::format(
            "line 1: format version {} (this leakmon reads version {})", version, kTrendVersion));
      }
      continue;
    }
    if (line_number == 2) {
      if (line != header) throw std::runtime_error("line 2: unexpected columns");
      continue;
    }
    if (line.empty()) continue;
    // A crash mid-write cannot leave a short last row (files are replaced whole), so any
    // malformed row means the file is not what it claims to be.
    fields.clear();
    std::size_t from = 0;
    while (true) {
      const std::size_t comma = line.find(',', from);
      fields.push_back(line.substr(from, comma - from));
      if (comma == std::string_view::npos) break;
      from = comma + 1;
    }
    if (fields.size() != kTrendFields) {
      throw std::runtime_error(
          fmt::format("line {}: {} fields, expected {}", line_number, fields.size(), kTrendFields));
    }
    TrendPoint p;
    double* numbers[] = {&p.unix_time,
                         &p.index_p1,
                         &p.index_p2,
                         &p.score,
                         &p.raise_threshold,
                         &p.leak_lpm_per_mpa,
                         &p.leak_lpm_per_mpa_ci95,
                         &p.p1,
                         &p.p2,
                         &p.oil_temperature};
    for (std::size_t k = 0; k < std::size(numbers); ++k) {
      *numbers[k] = parse_number(fields[k], line_number, kTrendColumns[k]);
    }
    if (!std::isfinite(p.unix_time)) {
      throw std::runtime_error(fmt::format("line {}, field unix_time: not finite", line_number));
    }
    p.alarm = parse_small(fields[10], line_number, kTrendColumns[10], 3);
    p.learning = parse_small(fields[11], line_number, kTrendColumns[11], 1) == 1;
    p.suspended = parse_small(fields[12], line_number, kTrendColumns[12], 1) == 1;
    for (std::size_t k = 0; k < 3; ++k) {
      p.channel_status[k] = parse_small(fields[13 + k], line_number, kTrendColumns[13 + k], 255);
    }
    if (!points.empty() && !(p.unix_time > points.back().unix_time)) {
      throw std::runtime_error(
          fmt::format("line {}, field unix_time: not after the previous row", line_number));
    }
    points.push_back(p);
  }
  if (line_number < 2) throw std::runtime_error("truncated: no header");
  return points;
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

bool TrendHistory::restore(const std::string& actuator, const std::vector<TrendPoint>& points) {
  for (auto& series : actuators_) {
    if (series.name != actuator) continue;
    const std::size_t skip = points.size() > capacity_ ? points.size() - capacity_ : 0;
    FixedRing<TrendPoint> ring(capacity_);
    for (std::size_t i = skip; i < points.size(); ++i) ring.push(points[i]);
    for (std::size_t i = 0; i < series.points.size(); ++i) ring.push(series.points[i]);
    series.points = std::move(ring);
    return true;
  }
  return false;
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

void TrendHistory::record(double unix_time, const ServiceSnapshot& snapshot) {
  for (const auto& status : snapshot.actuators) {
    auto it = std::find_if(actuators_.begin(), actuators_.end(),
                           [&](const ActuatorSeries& s) { return s.name == status.name; });
    if (it == actuators_.end()) {
      actuators_.push_back({status.name, FixedRing<TrendPoint>(capacity_)});
      it = actuators_.end() - 1;
    }
    it->points.push(point_of(unix_time, status));
  }
  for (const auto& group : snapshot.groups) {
    auto it = std::find_if(groups_.begin(), groups_.end(),
                           [&](const GroupSeries& s) { return s.name == group.name; });
    const LatencySummary& latency = group.wakeup_latency;
    if (it == groups_.end()) {
      groups_.push_back({group.name, FixedRing<LoopPoint>(capacity_)});
      it = groups_.end() - 1;
      it->last_count = latency.count;
      it->last_sum_ns = latency.sum_ns;
    }
    LoopPoint p;
    p.unix_time = unix_time;
    const std::uint64_t cycles = latency.count - it->last_count;
    p.latency_mean_us = cycles == 0 ? kNaN
                                    : static_cast<double>(latency.sum_ns - it->last_sum_ns) /
                                          static_cast<double>(cycles) / 1e3;
    p.overruns = group.overruns;
    p.ring_drops = group.ring_drops;
    it->points.push(p);
    it->last_count = latency.count;
    it->last_sum_ns = latency.sum_ns;
  }
}

std::size_t TrendHistory::memory_bytes(std::size_t capacity, std::size_t actuators,
                                       std::size_t groups) {
  return capacity * (actuators * sizeof(TrendPoint) + groups * sizeof(LoopPoint));
}

std::size_t TrendHistory::memory_bytes() const {
  return memory_bytes(capacity_, actuators_.size(), groups_.size());
}

}  // namespace leakmon::views
