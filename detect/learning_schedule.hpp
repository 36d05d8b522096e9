// When a detector learns: it ignores the start-up transient (`settle_seconds`), then treats the
// next `learn_seconds` of observations as the healthy reference of this rig. A leak present
// while learning becomes part of the baseline; reset() after maintenance starts over.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string_view>

#include "detect/detector_state.hpp"

namespace leakmon::detect {

struct LearningSchedule {
  double settle_seconds = 2.0;
  double learn_seconds = 90.0;

  std::size_t settle_hops(double hop_seconds) const {
    return static_cast<std::size_t>(std::lround(settle_seconds / hop_seconds));
  }
  std::size_t learn_hops(double hop_seconds) const {
    return static_cast<std::size_t>(std::lround(learn_seconds / hop_seconds));
  }
};

// `seconds` in whole hops, at least one (a block, a judging window).
inline std::size_t hops_in(double seconds, double hop_seconds) {
  return std::max<std::size_t>(static_cast<std::size_t>(std::lround(seconds / hop_seconds)), 1);
}

// Where a detector stands in its schedule, counted in hops: the preamble every detector
// shares. Per hop: count_hop() (false while settling: ignore the hop), hops_left() for the
// decision while not learned(), and at period_over() the detector learns and calls
// set_learned() (a detector that still lacks data may learn later).
class LearningClock {
 public:
  LearningClock(const LearningSchedule& schedule, double hop_seconds)
      : settle_hops_(schedule.settle_hops(hop_seconds)),
        learn_hops_(std::max<std::size_t>(schedule.learn_hops(hop_seconds), 1)) {}

  std::size_t settle_hops() const { return settle_hops_; }
  std::size_t learn_hops() const { return learn_hops_; }

  // Counts this hop; false while it falls in the settling time.
  bool count_hop() { return ++hops_seen_ > settle_hops_; }
  // Hops until learned (settling included; 0 once the learning period is over), for
  // Decision::learning_hops_left.
  double hops_left() const {
    const std::size_t total = settle_hops_ + learn_hops_;
    return static_cast<double>(hops_seen_ >= total ? 0 : total - hops_seen_);
  }
  // The hop just counted, from 0 at the first hop of the learning period (after settling).
  std::size_t learning_hop() const { return hops_seen_ - settle_hops_ - 1; }
  // The learning period ended with the hop just counted, or before it.
  bool period_over() const { return hops_seen_ - settle_hops_ >= learn_hops_; }

  bool learned() const { return learned_; }
  void set_learned() { learned_ = true; }
  // The learning period starts over with the next hop (its data did not suffice; no settling).
  void restart_period() { hops_seen_ = settle_hops_; }
  void reset() {
    hops_seen_ = 0;
    learned_ = false;
  }

  // `prefix.hops_seen` and `prefix.learned`.
  void save(DetectorState& state, std::string_view prefix) const;
  void restore(const DetectorState& state, std::string_view prefix);

 private:
  std::size_t settle_hops_, learn_hops_;
  std::size_t hops_seen_ = 0;
  bool learned_ = false;
};

// Target false-alarm rate -> the threshold of a log-likelihood-ratio CUSUM that judges one
// block every `block_seconds`. The average run length to a false alarm of such a CUSUM is at
// least exp(h) blocks (Lorden's bound, checked by `leakmon evaluate`), so h = ln(ARL0).
inline double cusum_threshold_for(double false_alarms_per_hour, double block_seconds) {
  const double blocks_between_alarms = 3600.0 / (false_alarms_per_hour * block_seconds);
  return std::log(blocks_between_alarms);
}

// The same target for a CUSUM whose increments are the Gaussian log-likelihood ratio
// shift (z - shift / 2) of blocks with unit spread, once the shift in spreads is known. Lorden's
// bound above ignores the overshoot and the walk's variance; Siegmund's approximation
// ARL0 = (exp(x) - x - 1) / (shift^2 / 2), x = h + 1.166 shift, is accurate for such a walk
// (within a few per cent in its published checks), and gives 0.75-0.85 of ln(ARL0) at the
// shifts the pressure features have (0.5-1 spread per block): the threshold the information
// bound's ideal detector uses (docs/detection.md, issue 23). Never above Lorden's threshold.
inline double cusum_threshold_for_shift(double false_alarms_per_hour, double block_seconds,
                                        double shift_in_spreads) {
  const double lorden = cusum_threshold_for(false_alarms_per_hour, block_seconds);
  const double shift = std::abs(shift_in_spreads);
  if (!(shift > 0.0) || !std::isfinite(shift)) return lorden;
  const double target = std::exp(lorden) * shift * shift / 2.0;  // = exp(x) - x - 1
  // x = ln(target + x + 1): a contraction for x > 0 (derivative 1 / (target + x + 1) < 1).
  double x = std::log1p(target);
  for (int i = 0; i < 50; ++i) x = std::log(target + x + 1.0);
  return std::clamp(x - 1.166 * shift, 0.0, lorden);
}

}  // namespace leakmon::detect
