// Page's one-sided CUSUM on log-likelihood-ratio increments: S = max(0, S + llr). It raises
// when S >= h; S is capped at `cap` so that it can come back below the clear level within a
// bounded time once the evidence stops (after a repair).
#pragma once

#include <algorithm>

namespace leakmon::detect {

class Cusum {
 public:
  Cusum(double threshold, double cap_factor = 4.0)
      : threshold_(threshold), cap_(cap_factor * threshold) {}

  double add(double llr_increment) {
    sum_ = std::clamp(sum_ + llr_increment, 0.0, cap_);
    return sum_;
  }
  double value() const { return sum_; }
  double threshold() const { return threshold_; }
  // The statistic in units of its threshold: 1 means "raise".
  double normalised() const { return sum_ / threshold_; }
  void reset() { sum_ = 0.0; }
  // A saved value() (a restart); clamped to the statistic's range.
  void restore(double sum) { sum_ = std::clamp(sum, 0.0, cap_); }

 private:
  double threshold_;
  double cap_;
  double sum_ = 0.0;
};

}  // namespace leakmon::detect
