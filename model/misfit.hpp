// Where a model's leftover misfit lives (issue 12, FORMATS.md `unexplained`): the channel whose
// held-out error stands furthest above the noise floor, the regressor that error follows best,
// the frequency band holding it, and how it changes over the capture. A rig engineer reads the
// answer as "p1 is wrong in proportion to the load pressure, below 2 Hz, growing over time".
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "model/segment_predictor.hpp"

namespace leakmon::model {

struct RegressorFit {
  std::string regressor;     // load_pressure, velocity, velocity_sign, dp_dt, du_dt, ...
  double correlation = 0.0;  // of the residual's rate with it, over held-out samples
};

struct Misfit {
  std::string channel;                           // x, p1 or p2
  std::array<double, 3> channel_nrmse{};         // held-out, x, p1, p2
  std::array<double, 3> channel_floor{};         // the noise floor of each
  std::vector<RegressorFit> regressors;          // best first
  double band_low_hz = 0.0, band_high_hz = 0.0;  // band with most of the excess power
  double band_share = 0.0;                       // its share of the excess power
  // The held-out squared error of the last third of the capture over the first third's, and
  // the Welch t statistic of the per-segment log errors between them.
  double late_over_early = 1.0;
  double trend_t = 0.0;
  bool drifts = false;  // the misfit changes over the capture (trend or parameter drift)
};

// `floor`: per-channel noise floor (SegmentPredictor::noise_floor) on the same segments.
Misfit locate_misfit(const SegmentPredictor& predictor, const ModelParameters& parameters,
                     std::span<const Segment> segments, const std::array<double, 3>& floor);

// One sentence for the report.
std::string describe(const Misfit& m);

}  // namespace leakmon::model
