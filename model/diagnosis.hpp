// The model-check workflow of issue 7: calibrate the nominal model on the fitting part, extend
// it with each effect of the library in turn (fitted together with the calibration), score
// every extension on held-out data, and name the best one only when its gain is significant.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/calibration_fit.hpp"
#include "model/measured_record.hpp"
#include "model/segment_predictor.hpp"

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
  double significance = 0.0;  // paired t statistic of the held-out per-segment improvement
  bool plausible = false;     // fitted main parameter is a physical instance of the effect
  bool refined = false;       // fitted with the calibration on all fitting segments
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
  double min_score = 0.02;
  double min_significance = 2.5;
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
  ModelParameters nominal, extended;  // the two models compared
  std::optional<double> ripple_line_hz;
};

Diagnosis diagnose(const MeasuredRecord& record, const DiagnosisSettings& settings = {});

}  // namespace leakmon::model
