// Least-squares fit of a model to the fitting segments (multiple shooting), with Eigen's
// Levenberg-Marquardt (unsupported/Eigen/LevenbergMarquardt, MINPACK's algorithm). The
// calibratable parameters beta, Kv, m, b are always free; an effect candidate adds its own.
#pragma once

#include <array>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "model/effect_library.hpp"
#include "model/segment_predictor.hpp"

namespace leakmon::model {

using CalibrationMask = std::array<bool, 4>;  // beta, Kv, m, b

struct FitSettings {
  int max_iterations = 15;     // solver steps (each with a Jacobian: one simulation per unknown)
  bool uncertainties = false;  // also compute standard errors (one more Jacobian)
  CalibrationMask free_calibration = {true, true, true, true};  // others stay at `start`
  // The rig's stated beta, Kv, m, b: the solver's scales and the bounds (twice MODEL.md's
  // calibratable ranges) are relative to them. The paper's rig unless a rig is described.
  Calibration stated;
  // Answer the solver's repeated requests for the same point from the evaluations kept (the
  // same numbers, one simulation fewer per solver step); false simulates every request.
  bool reuse_evaluations = true;
  // A Jacobian column of an effect that starts inside the capture simulates only the segments
  // that reach its onset (the others' residuals cannot change: the same numbers, a share of
  // the simulation saved); false simulates every segment for every column.
  bool skip_segments_before_onset = true;
};

struct FitResult {
  ModelParameters parameters;        // the fitted model
  std::vector<double> values;        // the candidate's parameters [SI], clamped as applied
  std::vector<double> value_errors;  // their standard errors (when requested), same order
  Calibration calibration_errors;    // standard errors of beta, Kv, m, b (when requested)
  double cost = 0.0;                 // mean squared scaled residual on the fitting segments
  int evaluations = 0;
};

// `candidate` null fits the calibrated nominal model. `start` gives the calibration's starting
// point (effects in it are ignored).
FitResult fit_model(const SegmentPredictor& predictor, std::span<const Segment> segments,
                    const EffectCandidate* candidate, const Calibration& start,
                    const FitSettings& settings = {});

// `start` with beta replaced by the value on a geometric grid across beta's bounds (steps of
// `relative_step`) whose model fits `segments` best, the others held. A lightly damped
// hydraulic mode rung in the data is matched only within a few per cent of its frequency
// (sqrt(beta)); from further away the fit damps the mode instead (b to its bound), and beta
// then has no gradient left to follow (docs/model-check.md, seed 770009).
Calibration best_beta_on_grid(const SegmentPredictor& predictor, std::span<const Segment> segments,
                              const Calibration& start, const Calibration& stated = {},
                              double relative_step = 0.02);

// The calibratable parameters (beta, Kv, m, b) that sit on the bound the fit holds them to
// (within `tolerance` of the bound interval's width): such a value is not a calibration but a
// sign that the model is compensating for something it lacks.
// `stated`: the rig's stated values the bounds are relative to.
std::vector<std::string> calibration_at_bound(const Calibration& c, const Calibration& stated = {},
                                              double tolerance = 0.002);
// `c` moved inside the bounds around `stated` (a start for a retry).
Calibration within_bounds(const Calibration& c, const Calibration& stated = {});
// The fit's bounds around `stated`: lower and upper calibration.
std::pair<Calibration, Calibration> calibration_bounds(const Calibration& stated = {});

}  // namespace leakmon::model
