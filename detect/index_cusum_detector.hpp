// Sequential test on the log of the wavelet index. The index of a healthy rig still moves with
// the operating point (the load pressure sets the valve's pressure drop and so how strongly the
// spool noise drives the hydraulic mode), so the detector learns, per rig, a quadratic model of
// the healthy log-index in the load pressure and tests the residual: blocks of one window
// length (nearly independent), a CUSUM for a drop of `design_drop`, its threshold set from the
// target false-alarm rate. Uses every chamber index the configuration acquires (their mean log).
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

#include "detect/cusum.hpp"
#include "detect/detector.hpp"
#include "detect/learning_schedule.hpp"
#include "sim/parameters.hpp"

namespace leakmon::detect {

struct IndexCusumOptions {
  LearningSchedule learning;
  bool use_p1 = true, use_p2 = true;    // which chamber indices to use (if acquired)
  sim::Parameters rig;                  // its ps [Pa] scales the load pressure regressor
  double design_drop = 0.08;            // relative index drop the CUSUM is tuned for
  double false_alarms_per_hour = 0.05;  // sets the threshold
  double block_seconds = 0.8;           // one window (400 samples at 500 Hz)
};

class IndexCusumDetector final : public Detector {
 public:
  IndexCusumDetector(const IndexCusumOptions& options, double hop_seconds);

  std::string_view name() const override { return "index_cusum"; }
  Decision update(const Observation& observation) override;
  double raise_threshold() const override { return 1.0; }
  double clear_threshold() const override { return 0.5; }
  void reset() override;

 private:
  // One block's means: the response and its regressors.
  struct Block {
    double log_index, load, load_squared, log_activity;
  };
  static constexpr int kRegressors = 4;
  double log_index_of(const Observation& observation) const;
  double load_of(const Observation& observation) const;
  double expected_log_index(const Block& block) const;
  bool add_to_block(double log_index, double load, Block& completed);
  void finish_learning();

  IndexCusumOptions options_;
  std::size_t settle_hops_, learn_hops_, block_hops_;
  std::size_t hops_seen_ = 0;
  std::vector<Block> learned_;  // reserved at construction
  bool learned_model_ = false;
  double coefficients_[kRegressors] = {0.0, 0.0, 0.0, 0.0};
  double block_sigma_ = kMissing;  // long-run std. dev. of a block's residual
  // The block being filled.
  std::size_t block_hop_ = 0, block_valid_ = 0;
  double sum_log_index_ = 0.0, sum_load_ = 0.0, sum_load_squared_ = 0.0, sum_activity_ = 0.0;
  double previous_load_ = kMissing;
  double last_expected_ = kMissing;
  Cusum cusum_;
};

}  // namespace leakmon::detect
