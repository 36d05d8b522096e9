#include "model/change_point.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace leakmon::model {

std::vector<Segment> segments_in_time_order(const SegmentPlan& plan) {
  std::vector<Segment> all(plan.fitting.begin(), plan.fitting.end());
  all.insert(all.end(), plan.held_out.begin(), plan.held_out.end());
  std::sort(all.begin(), all.end(),
            [](const Segment& a, const Segment& b) { return a.begin < b.begin; });
  return all;
}

std::vector<std::size_t> moving_segments(const MeasuredRecord& record,
                                         std::span<const Segment> segments, double share) {
  std::vector<double> ranges;
  for (const auto& seg : segments) {
    const auto first = record.x.begin() + static_cast<std::ptrdiff_t>(seg.begin);
    const auto [low, high] =
        std::minmax_element(first, first + static_cast<std::ptrdiff_t>(seg.length));
    ranges.push_back(*high - *low);
  }
  std::vector<std::size_t> out;
  if (ranges.empty()) return out;
  std::vector<double> sorted = ranges;
  const auto rank = static_cast<std::ptrdiff_t>(0.9 * static_cast<double>(sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + rank, sorted.end());
  const double threshold = share * sorted[static_cast<std::size_t>(rank)];
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (ranges[i] > threshold) out.push_back(i);
  }
  return out;
}

std::optional<ChangePoint> find_change_point(const MeasuredRecord& record,
                                             std::span<const Segment> segments,
                                             std::span<const double> log_errors,
                                             std::size_t min_side) {
  const std::size_t n = log_errors.size();
  if (n < 2 * min_side || segments.size() != n) return std::nullopt;
  // Prefix sums of the values and their squares: every split's two means and variances in
  // constant time.
  std::vector<double> sum(n + 1, 0.0), sum2(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    sum[i + 1] = sum[i] + log_errors[i];
    sum2[i + 1] = sum2[i] + log_errors[i] * log_errors[i];
  }
  const auto moments = [&](std::size_t a, std::size_t b) {  // [a, b)
    const auto count = static_cast<double>(b - a);
    const double mean = (sum[b] - sum[a]) / count;
    const double var = std::max((sum2[b] - sum2[a]) / count - mean * mean, 0.0) * count /
                       std::max(count - 1.0, 1.0);
    return std::pair{mean, var / count};
  };
  ChangePoint best;
  bool found = false;
  for (std::size_t j = min_side; j + min_side <= n; ++j) {
    const auto [before, before_var] = moments(0, j);
    const auto [after, after_var] = moments(j, n);
    const double se = std::sqrt(before_var + after_var);
    const double t = se > 0.0 ? (after - before) / se : 0.0;
    if (!found || t > best.statistic) {
      best = {j, record.t[segments[j].begin], t, after - before};
      found = true;
    }
  }
  if (!found) return std::nullopt;
  return best;
}

}  // namespace leakmon::model
