// When a detector learns: it ignores the start-up transient (`settle_seconds`), then treats the
// next `learn_seconds` of observations as the healthy reference of this rig. A leak present
// while learning becomes part of the baseline; reset() after maintenance starts over.
#pragma once

#include <cmath>
#include <cstddef>

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

// Target false-alarm rate -> the threshold of a log-likelihood-ratio CUSUM that judges one
// block every `block_seconds`. The average run length to a false alarm of such a CUSUM is at
// least exp(h) blocks (Lorden's bound, checked by `leakmon evaluate`), so h = ln(ARL0).
inline double cusum_threshold_for(double false_alarms_per_hour, double block_seconds) {
  const double blocks_between_alarms = 3600.0 / (false_alarms_per_hour * block_seconds);
  return std::log(blocks_between_alarms);
}

}  // namespace leakmon::detect
