#include "detect/paper_baseline_detector.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

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
  if (std::isnan(baseline_)) {
    const std::size_t total = settle_hops_ + learn_hops_;
    decision.learning_hops_left = static_cast<double>(hops_seen_ >= total ? 0 : total - hops_seen_);
  }
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

namespace leakmon::detect {

namespace {
constexpr int kPaperStateVersion = 1;
}  // namespace

DetectorState PaperBaselineDetector::export_state() const {
  DetectorState state(std::string(name()), kPaperStateVersion);
  state.put_count("hops_seen", hops_seen_);
  state.put("learned", learned_);
  state.put("baseline", baseline_);
  const std::vector<double> below(below_.begin(), below_.end());
  state.put("below", below);
  state.put_count("ring_next", ring_next_);
  state.put_count("ring_filled", ring_filled_);
  state.put_count("below_count", below_count_);
  return state;
}

void PaperBaselineDetector::import_state(const DetectorState& state) {
  reset();
  try {
    state.expect(name(), kPaperStateVersion);
    const auto& learned = state.get_list("learned");
    const auto& below = state.get_list("below");
    if (learned.size() > learned_.capacity())
      throw StateError(
          "paper: more learned hops than "
          "this configuration learns");
    if (below.size() != below_.size()) throw StateError("paper: judging window differs");
    const std::size_t ring_next = state.get_count("ring_next");
    const std::size_t ring_filled = state.get_count("ring_filled");
    if (ring_next >= below_.size() || ring_filled > below_.size()) {
      throw StateError("paper: ring position out of range");
    }
    std::size_t count = 0;
    for (std::size_t i = 0; i < below.size(); ++i) {
      if (below[i] != 0.0 && below[i] != 1.0) throw StateError("paper: verdict not 0 or 1");
      below_[i] = static_cast<unsigned char>(below[i]);
      count += below_[i];
    }
    if (count != state.get_count("below_count")) throw StateError("paper: verdict count differs");
    hops_seen_ = state.get_count("hops_seen");
    learned_.assign(learned.begin(), learned.end());
    baseline_ = state.get("baseline");
    ring_next_ = ring_next;
    ring_filled_ = ring_filled;
    below_count_ = count;
  } catch (...) {
    reset();
    throw;
  }
}

}  // namespace leakmon::detect
