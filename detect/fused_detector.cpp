#include "detect/fused_detector.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "detect/legacy_state.hpp"

namespace leakmon::detect {

FusedDetector::FusedDetector(std::vector<std::unique_ptr<Detector>> members)
    : members_(std::move(members)), member_decisions_(members_.size()) {}

void FusedDetector::reset() {
  for (auto& member : members_) member->reset();
  for (auto& decision : member_decisions_) decision = Decision{};
}

Decision FusedDetector::update(const Observation& observation) {
  Decision fused;
  fused.learning = false;
  fused.not_judged_reason = NotJudgedReason::none;
  for (std::size_t i = 0; i < members_.size(); ++i) {
    const Decision d = members_[i]->update(observation);
    member_decisions_[i] = d;
    fused.learning = fused.learning || d.learning;
    if (d.learning && !(d.learning_hops_left <= fused.learning_hops_left)) {
      fused.learning_hops_left = d.learning_hops_left;  // the slowest member decides
    }
    if (!std::isnan(d.score)) {
      const double relative = d.score / members_[i]->raise_threshold();
      if (std::isnan(fused.score) || relative > fused.score) fused.score = relative;
    }
    // Judged when a member judges; otherwise the first member's reason (the flow balance's).
    fused.judged = fused.judged || d.judged;
    if (!d.judged && fused.not_judged_reason == NotJudgedReason::none) {
      fused.not_judged_reason = d.not_judged_reason;
    }
    if (std::isnan(fused.index) && !std::isnan(d.index)) {
      fused.index = d.index;
      fused.baseline = d.baseline;
    }
    if (std::isnan(fused.leak_coefficient) && !std::isnan(d.leak_coefficient)) {
      fused.leak_coefficient = d.leak_coefficient;
      fused.leak_coefficient_ci = d.leak_coefficient_ci;
      fused.viscosity_ratio = d.viscosity_ratio;
    }
  }
  if (fused.judged) fused.not_judged_reason = NotJudgedReason::none;
  return fused;
}

}  // namespace leakmon::detect

namespace leakmon::detect {

namespace {
constexpr int kFusedStateVersion = 1;

// A member's key in the state: "m0", "m1", ... Not `"m" + std::to_string(i)`: GCC 12 at -O3
// reports a false -Wrestrict inside that operator+ (GCC bug 105329), which fails Release builds.
std::string member_key(std::size_t i) {
  std::string key(1, 'm');
  key += std::to_string(i);
  return key;
}
}  // namespace

DetectorState FusedDetector::export_state() const {
  DetectorState state(std::string(name()), kFusedStateVersion);
  state.put_count("members", members_.size());
  for (std::size_t i = 0; i < members_.size(); ++i) {
    state.put_nested(member_key(i), members_[i]->export_state());
  }
  return state;
}

void FusedDetector::import_state(const DetectorState& saved) {
  import_detector_state(*this, saved, kFusedStateVersion, [this](const DetectorState& state) {
    if (state.get_count("members") != members_.size()) throw StateError("member count");
    for (std::size_t i = 0; i < members_.size(); ++i) {
      members_[i]->import_state(state.get_nested(member_key(i)));
    }
  });
}

}  // namespace leakmon::detect
