// The paper's decision (Goharrizi, Sepehri and Wu): a leak is declared when the index stays
// below a healthy baseline. The paper picked its baseline (30 kPa) by eye; here it is learned
// as a quantile of this rig's healthy index, and "stays below" is the fraction of the last
// `window_seconds` of hops under it. Kept as the reference point the other detectors must beat.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>
#include <vector>

#include "detect/detector.hpp"
#include "detect/learning_schedule.hpp"
#include "detect/ring.hpp"

namespace leakmon::detect {

struct PaperBaselineOptions {
  LearningSchedule learning;
  double baseline_quantile = 0.5;  // learned baseline = this quantile of the healthy index
  double window_seconds = 10.0;    // judging window
  double raise_fraction = 0.9;     // "close to 90 % of the time" below the baseline
  double clear_fraction = 0.7;
  bool use_p2 = false;  // judge p2's index instead of p1's
};

class PaperBaselineDetector final : public Detector {
 public:
  PaperBaselineDetector(const PaperBaselineOptions& options, double hop_seconds);

  std::string_view name() const override { return "paper"; }
  bool needs_hydraulic_mode() const override { return true; }
  Decision update(const Observation& observation) override;
  double raise_threshold() const override { return options_.raise_fraction; }
  double clear_threshold() const override { return options_.clear_fraction; }
  void reset() override;
  DetectorState export_state() const override;
  void import_state(const DetectorState& state) override;
  double learning_seconds() const override {
    return options_.learning.settle_seconds + options_.learning.learn_seconds;
  }

  // The layout export_state() writes (legacy_state.hpp reads the ones before).
  static constexpr int kStateVersion = 2;

 private:
  struct Verdict {
    bool below = false;  // the hop's index was below the baseline
  };
  static constexpr std::array<RecordField<Verdict>, 1> kVerdictFields = {
      record_field<&Verdict::below>("below")};

  PaperBaselineOptions options_;
  LearningClock clock_;
  std::vector<double> learned_;  // healthy indices, reserved at construction
  double baseline_ = kMissing;
  Ring<Verdict> window_;  // the last window's verdicts
  std::size_t below_count_ = 0;
};

}  // namespace leakmon::detect
