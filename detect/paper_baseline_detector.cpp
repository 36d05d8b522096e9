#include "detect/paper_baseline_detector.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::detect {

PaperBaselineDetector::PaperBaselineDetector(const PaperBaselineOptions& options,
                                             double hop_seconds)
    : options_(options),
      settle_hops_(options.learning.settle_hops(hop_seconds)),
      learn_hops_(std::max<std::size_t>(options.learning.learn_hops(hop_seconds), 1)),
      below_(std::max<std::size_t>(
          static_cast<std::size_t>(std::lround(options.window_seconds / hop_seconds)), 1)) {
  learned_.reserve(learn_hops_);
}

void PaperBaselineDetector::reset() {
  hops_seen_ = 0;
  learned_.clear();
  baseline_ = kMissing;
  std::fill(below_.begin(), below_.end(), 0);
  ring_next_ = ring_filled_ = below_count_ = 0;
}

Decision PaperBaselineDetector::update(const Observation& observation) {
  const double index = options_.use_p2 ? observation.index_p2 : observation.index_p1;
  Decision decision;
  decision.index = index;
  ++hops_seen_;
  if (hops_seen_ <= settle_hops_) return decision;

  if (std::isnan(baseline_)) {
    if (!std::isnan(index)) learned_.push_back(index);  // capacity reserved: never reallocates
    if (hops_seen_ - settle_hops_ >= learn_hops_ && !learned_.empty()) {
      const auto nth = learned_.begin() +
                       static_cast<std::ptrdiff_t>(std::lround(
                           options_.baseline_quantile * static_cast<double>(learned_.size() - 1)));
      std::nth_element(learned_.begin(), nth, learned_.end());
      baseline_ = *nth;
    }
    return decision;
  }

  decision.learning = false;
  decision.baseline = baseline_;
  if (std::isnan(index)) return decision;
  const unsigned char is_below = index < baseline_ ? 1 : 0;
  if (ring_filled_ == below_.size()) {
    below_count_ -= below_[ring_next_];
  } else {
    ++ring_filled_;
  }
  below_[ring_next_] = is_below;
  below_count_ += is_below;
  ring_next_ = (ring_next_ + 1) % below_.size();
  if (ring_filled_ == below_.size()) {
    decision.score = static_cast<double>(below_count_) / static_cast<double>(below_.size());
  }
  return decision;
}

}  // namespace leakmon::detect
