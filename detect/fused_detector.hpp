// Runs several detectors on the same observations and raises when any of them would: the
// score is the largest of their scores, each divided by its own raise threshold. Each member
// gets a share of the false-alarm budget (the factory sets that up), so the union keeps the
// target rate. The leak size comes from the first member that can size a leak.
#pragma once

#include <algorithm>
#include <memory>
#include <string_view>
#include <vector>

#include "detect/detector.hpp"

namespace leakmon::detect {

class FusedDetector final : public Detector {
 public:
  explicit FusedDetector(std::vector<std::unique_ptr<Detector>> members);

  std::string_view name() const override { return "fused"; }
  Decision update(const Observation& observation) override;
  double raise_threshold() const override { return 1.0; }
  double clear_threshold() const override { return 0.5; }
  void reset() override;
  DetectorState export_state() const override;
  void import_state(const DetectorState& state) override;
  void resume_after_gap() override {
    for (auto& member : members_) member->resume_after_gap();
  }
  // The fused score needs every member: the longest learning decides.
  double learning_seconds() const override {
    double longest = 0.0;
    for (const auto& member : members_) longest = std::max(longest, member->learning_seconds());
    return longest;
  }

  // Blind without the mode only when every member is.
  bool needs_hydraulic_mode() const override {
    return std::all_of(members_.begin(), members_.end(),
                       [](const auto& member) { return member->needs_hydraulic_mode(); });
  }

  // The first member's that found one.
  std::optional<LearnedChange> learned_change() const override {
    for (const auto& member : members_) {
      if (auto change = member->learned_change()) return change;
    }
    return std::nullopt;
  }

  // The latest decision of each member (same order as given), for diagnostics and evaluation.
  const std::vector<Decision>& member_decisions() const { return member_decisions_; }
  const std::vector<std::unique_ptr<Detector>>& members() const { return members_; }

 private:
  std::vector<std::unique_ptr<Detector>> members_;
  std::vector<Decision> member_decisions_;
};

}  // namespace leakmon::detect
