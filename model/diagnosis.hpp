// The model-check workflow of issue 7: calibrate the nominal model on the fitting part, extend
// it with each effect of the library in turn (fitted together with the calibration), score
// every extension on held-out data, and name the best one only when its gain is significant.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/calibration_fit.hpp"
#include "model/force_balance.hpp"
#include "model/measured_record.hpp"
#include "model/segment_predictor.hpp"
#include "model/spectral_line.hpp"

namespace leakmon::model {

struct NamedValue {
  std::string name;    // MODEL.md's parameter name
  double value = 0.0;  // SI
  double error = 0.0;  // standard error, 0 when not computed
  std::string text;    // non-empty for discrete parameters ("p2"), which then have no value
  bool is_text() const { return !text.empty(); }
};

struct RankedEffect {
  std::string effect;
  // Share of the nominal model's held-out squared error it removes: 1 - the geometric mean
  // over held-out segments of error after / error before.
  double score = 0.0;
  // The larger of the paired t statistic and Yuen's 20 %-trimmed paired t statistic of the
  // held-out per-segment log improvement (diagnosis.cpp says why both).
  double significance = 0.0;
  bool plausible = false;  // fitted main parameter is a physical instance of the effect
  bool refined = false;    // fitted with the calibration on all fitting segments
  std::vector<NamedValue> params;
  FitResult fit;
};

struct DiagnosisSettings {
  SplitSettings split;
  std::size_t max_fitting_segments = 24;
  std::size_t max_held_out_segments = 60;
  std::size_t screening_segments = 12;
  int screening_iterations = 10;
  std::size_t refined_effects = 4;
  FitSettings fit;
  // Naming a cause needs both: the extension removes at least this share of the calibrated
  // nominal model's held-out squared error, and it does so consistently over the held-out
  // segments (paired t statistic). docs/model-check.md explains the values.
  double min_score = 0.005;
  double min_significance = 2.5;
  // A supply ripple is named on its own evidence, the held-out coherent line test of
  // spectral_line.hpp: z >= 4.5 happens by chance once in about 300 000 clean captures.
  double min_line_z = 4.5;
  // Take m from the force balance (force_balance.hpp) instead of fitting it; b starts there.
  bool use_force_balance = true;
};

struct Diagnosis {
  std::string cause = "none";
  std::vector<NamedValue> params;  // the cause's parameters with standard errors
  Calibration calibrated;          // of the reported model (the cause's fit, or nominal)
  Calibration calibrated_errors;
  std::vector<RankedEffect> ranking;  // every effect, best first
  double nrmse_before = 0.0;          // held-out, calibrated nominal model
  double nrmse_after = 0.0;           // held-out, model extended with the cause
  SegmentPlan plan;
  std::vector<Segment> fitting_used, held_out_used;
  ModelParameters nominal, extended;        // the two models compared
  std::optional<SpectralLine> ripple_line;  // the capture's most prominent line and its test
  bool ripple_line_significant = false;
  double min_line_z = 0.0;     // the threshold it was held to
  ForceBalance force_balance;  // m (and a first b) from the measured force balance
};

Diagnosis diagnose(const MeasuredRecord& record, const DiagnosisSettings& settings = {});

}  // namespace leakmon::model
