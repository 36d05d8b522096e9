#include "model/change_point.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <Eigen/Dense>

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

std::vector<std::vector<double>> segment_excitation(const MeasuredRecord& record,
                                                    std::span<const Segment> segments) {
  // Floors below any transducer's resolution keep a perfectly still segment's log finite.
  constexpr double kRangeFloor = 1e-9;    // [m]
  constexpr double kChangeFloor = 1e-12;  // [m per sample]
  std::vector<std::vector<double>> out(2);
  for (const auto& seg : segments) {
    double low = record.x[seg.begin], high = low, change2 = 0.0;
    for (std::size_t i = seg.begin + 1; i < seg.begin + seg.length; ++i) {
      low = std::min(low, record.x[i]);
      high = std::max(high, record.x[i]);
      const double step = record.x[i] - record.x[i - 1];
      change2 += step * step;
    }
    const double changes = static_cast<double>(std::max<std::size_t>(seg.length, 2) - 1);
    out[0].push_back(std::log(std::max(high - low, kRangeFloor)));
    out[1].push_back(std::log(std::max(std::sqrt(change2 / changes), kChangeFloor)));
  }
  return out;
}

std::optional<ChangePoint> find_change_point_beyond_excitation(
    const MeasuredRecord& record, std::span<const Segment> segments,
    std::span<const double> log_errors, const std::vector<std::vector<double>>& excitation,
    std::size_t min_side) {
  const std::size_t n = log_errors.size();
  const std::size_t k = excitation.size() + 1;  // intercept and regressors
  if (n < 2 * min_side || segments.size() != n || n <= k + 1) return std::nullopt;
  for (const auto& regressor : excitation) {
    if (regressor.size() != n) return std::nullopt;
  }
  // The regressors' Gram matrix and their products with y over every segment, and over the
  // segments from j on (the step's column) as suffix sums: each split's normal equations are
  // then assembled in O(k^2).
  Eigen::MatrixXd X(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(k));
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    X(row, 0) = 1.0;
    for (std::size_t r = 0; r + 1 < k; ++r)
      X(row, static_cast<Eigen::Index>(r + 1)) = excitation[r][i];
    y(row) = log_errors[i];
  }
  const Eigen::MatrixXd gram = X.transpose() * X;
  const Eigen::VectorXd xty = X.transpose() * y;
  const double yty = y.squaredNorm();
  std::vector<Eigen::VectorXd> tail_x(n + 1, Eigen::VectorXd::Zero(static_cast<Eigen::Index>(k)));
  std::vector<double> tail_y(n + 1, 0.0);
  for (std::size_t i = n; i-- > 0;) {
    tail_x[i] = tail_x[i + 1] + X.row(static_cast<Eigen::Index>(i)).transpose();
    tail_y[i] = tail_y[i + 1] + log_errors[i];
  }
  const auto size = static_cast<Eigen::Index>(k + 1);
  Eigen::MatrixXd normal(size, size);
  Eigen::VectorXd rhs(size);
  normal.topLeftCorner(size - 1, size - 1) = gram;
  rhs.head(size - 1) = xty;
  ChangePoint best;
  bool found = false;
  for (std::size_t j = min_side; j + min_side <= n; ++j) {
    normal.topRightCorner(size - 1, 1) = tail_x[j];
    normal.bottomLeftCorner(1, size - 1) = tail_x[j].transpose();
    normal(size - 1, size - 1) = static_cast<double>(n - j);
    rhs(size - 1) = tail_y[j];
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(normal);
    if (!lu.isInvertible()) continue;  // the step is a combination of the regressors here
    const Eigen::MatrixXd inverse = lu.inverse();
    const Eigen::VectorXd beta = inverse * rhs;
    const double residual = std::max(yty - beta.dot(rhs), 0.0);
    const double sigma2 = residual / static_cast<double>(n - k - 1);
    const double variance = sigma2 * inverse(size - 1, size - 1);
    const double t = variance > 0.0 ? beta(size - 1) / std::sqrt(variance) : 0.0;
    if (!found || t > best.statistic) {
      best = {j, record.t[segments[j].begin], t, beta(size - 1)};
      found = true;
    }
  }
  if (!found) return std::nullopt;
  return best;
}

}  // namespace leakmon::model
