// Page's one-sided CUSUM on the log-likelihood-ratio increments of judged blocks:
// S = max(0, S + llr). It raises when S >= h; S is capped at `cap_factor` h so that it can come
// back below the clear level within a bounded time once the evidence stops (after a repair).
//
// It can keep the value it had before each of the last `history_blocks` judged blocks, so
// that blocks found afterwards to have been judged against the wrong reference (those after a
// supply step that showed only later) are taken back out of it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string_view>

#include "detect/detector_state.hpp"
#include "detect/ring.hpp"

namespace leakmon::detect {

class BlockCusum {
 public:
  explicit BlockCusum(double threshold, std::size_t history_blocks = 0, double cap_factor = 4.0)
      : threshold_(threshold),
        cap_factor_(cap_factor),
        cap_(cap_factor * threshold),
        history_(history_blocks) {}

  // The block that ended at t; its value before is remembered (with a history).
  double add(double t, double llr_increment) {
    history_.push({t, sum_});
    sum_ = std::clamp(sum_ + llr_increment, 0.0, cap_);
    return sum_;
  }
  // Back to the value before the oldest remembered block that ended after t (none: unchanged).
  void take_back_after(double t);

  double value() const { return sum_; }
  double threshold() const { return threshold_; }
  // A threshold known only once the spread of a block is learned (the statistic keeps its value).
  void set_threshold(double threshold) {
    threshold_ = threshold;
    cap_ = cap_factor_ * threshold;
    set(sum_);
  }
  // The statistic in units of its threshold: 1 means "raise".
  double normalised() const { return sum_ / threshold_; }
  void reset() {
    sum_ = 0.0;
    history_.clear();
  }
  // The history is on a clock that no longer runs (a restart after a gap).
  void forget_history() { history_.clear(); }

  // `prefix.value`, and with a history `prefix.history.{t,before,next}`.
  void save(DetectorState& state, std::string_view prefix) const;
  void restore(const DetectorState& state, std::string_view prefix);

 private:
  struct Entry {
    double t, before;
  };
  static constexpr std::array<RecordField<Entry>, 2> kEntryFields = {
      record_field<&Entry::t>("t"), record_field<&Entry::before>("before")};
  void set(double sum) { sum_ = std::clamp(sum, 0.0, cap_); }

  double threshold_;
  double cap_factor_;
  double cap_;
  double sum_ = 0.0;
  Ring<Entry> history_;
};

// The learned block spread comes from ~100 blocks; inflate it to its one-sided 95 % upper
// confidence bound so that a lucky learning period does not set a hair trigger.
inline double upper_sigma_bound(double sigma, std::size_t blocks) {
  if (blocks < 2) return sigma;
  return sigma * (1.0 + 1.645 / std::sqrt(2.0 * static_cast<double>(blocks - 1)));
}

// Neighbouring blocks share an operating point and the CUSUM sums them: their lag-1
// correlation (sum r_k r_(k-1) / sum r_k^2, clamped to [0, 0.8]) ...
inline double lag_one_correlation(double sum_lag, double sum_sq) {
  return std::clamp(sum_lag / sum_sq, 0.0, 0.8);
}
// ... makes the spread a CUSUM block is scaled by the AR(1) long-run one,
// sigma sqrt((1 + rho) / (1 - rho)), of the upper bound above.
inline double cusum_block_sigma(double sigma, std::size_t blocks, double rho) {
  return upper_sigma_bound(sigma, blocks) * std::sqrt((1.0 + rho) / (1.0 - rho));
}

}  // namespace leakmon::detect
