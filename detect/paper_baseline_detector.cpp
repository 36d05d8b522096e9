#include "detect/paper_baseline_detector.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "detect/legacy_state.hpp"

namespace leakmon::detect {

PaperBaselineDetector::PaperBaselineDetector(const PaperBaselineOptions& options,
                                             double hop_seconds)
    : options_(options),
      clock_(options.learning, hop_seconds),
      window_(hops_in(options.window_seconds, hop_seconds)) {
  learned_.reserve(clock_.learn_hops());
}

void PaperBaselineDetector::reset() {
  clock_.reset();
  learned_.clear();
  baseline_ = kMissing;
  window_.clear();
  below_count_ = 0;
}

namespace {
Decision judged(Decision decision) {
  decision.judge_by_score();
  return decision;
}
}  // namespace

Decision PaperBaselineDetector::update(const Observation& observation) {
  const double index = options_.use_p2 ? observation.index_p2 : observation.index_p1;
  Decision decision;
  decision.index = index;
  const bool past_settling = clock_.count_hop();
  if (!clock_.learned()) decision.learning_hops_left = clock_.hops_left();
  if (!past_settling) return judged(decision);

  if (!clock_.learned()) {
    if (!std::isnan(index)) learned_.push_back(index);  // capacity reserved: never reallocates
    if (clock_.period_over() && !learned_.empty()) {
      const auto nth = learned_.begin() +
                       static_cast<std::ptrdiff_t>(std::lround(
                           options_.baseline_quantile * static_cast<double>(learned_.size() - 1)));
      std::nth_element(learned_.begin(), nth, learned_.end());
      baseline_ = *nth;
      clock_.set_learned();
    }
    return judged(decision);
  }

  decision.learning = false;
  decision.baseline = baseline_;
  if (std::isnan(index)) return judged(decision);
  const bool below = index < baseline_;
  if (window_.full() && window_.oldest().below) --below_count_;
  window_.push({below});
  if (below) ++below_count_;
  if (window_.full()) {
    decision.score = static_cast<double>(below_count_) / static_cast<double>(window_.capacity());
  }
  return judged(decision);
}

DetectorState PaperBaselineDetector::export_state() const {
  DetectorState state(std::string(name()), kStateVersion);
  clock_.save(state, "learning");
  state.put("learned", learned_);
  state.put("baseline", baseline_);
  save_ring(state, "window", window_, kVerdictFields);
  return state;
}

void PaperBaselineDetector::import_state(const DetectorState& saved) {
  import_detector_state(*this, saved, kStateVersion, [this](const DetectorState& state) {
    clock_.restore(state, "learning");
    const auto& learned = state.get_list("learned");
    if (learned.size() > learned_.capacity()) {
      throw StateError("more learned hops than this configuration learns");
    }
    learned_.assign(learned.begin(), learned.end());
    baseline_ = state.get("baseline");
    if (clock_.learned() == std::isnan(baseline_)) {
      throw StateError("learned, but no baseline (or the reverse)");
    }
    restore_ring(state, "window", window_, kVerdictFields);
    for (const Verdict& v : window_.stored()) below_count_ += v.below ? 1 : 0;
  });
}

}  // namespace leakmon::detect
