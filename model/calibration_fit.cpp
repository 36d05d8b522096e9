#include "model/calibration_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "model/recent_results.hpp"

namespace leakmon::model {
namespace {

// Solver coordinates: the calibration as value / scale, an effect parameter as
// 1 + (value - initial) / scale, so that every unknown starts near 1 and a unit step in any
// of them is a comparable change of the model.
constexpr int kCalibrationCount = 4;  // beta, Kv, m, b
// On the paper's rig; on another rig each scale follows its stated value (Scales below).
constexpr double kScales[kCalibrationCount] = {1e8, 1e-7, 1.0, 100.0};
// Bounds in solver units: twice MODEL.md's calibratable ranges (beta +-25 %, Kv +-10 %,
// m +-20 %, b +-30 %) around the stated value, so that a discrepancy cannot be absorbed by an
// absurd calibration (a 50 kg piston, say) instead of showing as an effect.
constexpr double kLower[kCalibrationCount] = {3.5, 2.712, 6.0, 1.2};
constexpr double kUpper[kCalibrationCount] = {10.5, 4.068, 14.0, 4.8};

// The solver's scales for a rig whose stated calibratable values are `stated`: the paper's
// scales times stated / the paper's value, so that the solver units and the bounds in them
// mean the same relative ranges on every rig (on the paper's rig exactly the constants).
struct Scales {
  double value[kCalibrationCount];
  explicit Scales(const Calibration& stated) {
    const Calibration paper;
    const double ratio[kCalibrationCount] = {stated.beta / paper.beta, stated.Kv / paper.Kv,
                                             stated.m / paper.m, stated.b / paper.b};
    for (int i = 0; i < kCalibrationCount; ++i) {
      value[i] = ratio[i] == 1.0 ? kScales[i] : kScales[i] * ratio[i];
    }
  }
  double operator[](int i) const { return value[i]; }
};

// An effect parameter beyond a bound is mirrored back into [lower, upper] rather than clamped:
// a clamped parameter has no gradient, and a solver step that overshoots the bound (the first
// steps are large) would leave it stuck there (a slow spool "found" at tau = 0.5 ms, say).
double reflected(double value, double lower, double upper) {
  const double width = upper - lower;
  if (width <= 0.0) return lower;
  double u = std::fmod(value - lower, 2.0 * width);
  if (u < 0.0) u += 2.0 * width;
  return lower + (u <= width ? u : 2.0 * width - u);
}

// Calibrated value `index` (beta, Kv, m, b: the order of kLower and kUpper) of `c`.
double& calibration_value(Calibration& c, int index) {
  double* values[kCalibrationCount] = {&c.beta, &c.Kv, &c.m, &c.b};
  return *values[index];
}

class SegmentFitProblem : public Eigen::DenseFunctor<double> {
 public:
  // Only the calibration parameters flagged in `free` are unknowns; the others stay at `start`.
  SegmentFitProblem(const SegmentPredictor& predictor, std::span<const Segment> segments,
                    const EffectCandidate* candidate, const Calibration& start,
                    const CalibrationMask& free, const Calibration& stated, bool reuse_evaluations,
                    bool skip_segments_before_onset)
      : Eigen::DenseFunctor<double>(
            static_cast<int>(std::count(free.begin(), free.end(), true)) +
                static_cast<int>(candidate ? candidate->parameters.size() : 0),
            static_cast<int>(SegmentPredictor::residual_count(segments))),
        predictor_(predictor),
        segments_(segments),
        candidate_(candidate),
        start_(start),
        scales_(stated),
        reuse_evaluations_(reuse_evaluations) {
    for (int i = 0; i < kCalibrationCount; ++i) {
      if (free[static_cast<std::size_t>(i)]) calibration_slot_[i] = first_effect_++;
    }
    if (candidate && skip_segments_before_onset) collect_late(*candidate, starts_late_);
    starts_late_.resize(candidate ? candidate->parameters.size() : 0, false);
    if (std::find(starts_late_.begin(), starts_late_.end(), true) != starts_late_.end()) {
      // The onset is the candidate's, the same at every point of the solver.
      const double onset_s = model(start_point()).onset_s;
      std::size_t offset = 0;
      for (const auto& seg : segments_) {
        if (predictor_.reaches(seg, onset_s)) {
          later_.push_back(seg);
          later_offsets_.push_back(offset);
        }
        offset += SegmentPredictor::residual_count({&seg, 1});
      }
      later_residuals_.resize(SegmentPredictor::residual_count(later_));
    }
  }

  int first_effect() const { return first_effect_; }
  int calibration_slot(int i) const { return calibration_slot_[i]; }

  InputType start_point() const {
    InputType theta = InputType::Ones(inputs());
    const double start[kCalibrationCount] = {start_.beta, start_.Kv, start_.m, start_.b};
    for (int i = 0; i < kCalibrationCount; ++i) {
      if (calibration_slot_[i] >= 0) theta[calibration_slot_[i]] = start[i] / scales_[i];
    }
    return theta;
  }

  ModelParameters model(const InputType& theta) const {
    ModelParameters p;
    p.calibration = start_;
    for (int i = 0; i < kCalibrationCount; ++i) {
      if (calibration_slot_[i] < 0) continue;
      calibration_value(p.calibration, i) =
          std::clamp(theta[calibration_slot_[i]], kLower[i], kUpper[i]) * scales_[i];
    }
    if (candidate_) candidate_->apply(p, effect_values(theta));
    return p;
  }

  std::vector<double> effect_values(const InputType& theta) const {
    std::vector<double> v;
    if (!candidate_) return v;
    for (std::size_t i = 0; i < candidate_->parameters.size(); ++i) {
      const auto& fp = candidate_->parameters[i];
      const double t = theta[first_effect_ + static_cast<int>(i)];
      v.push_back(reflected(fp.initial + (t - 1.0) * fp.scale, fp.lower, fp.upper));
    }
    return v;
  }

  // The solver asks for the residuals at a point it has evaluated before: its Jacobian is
  // taken where the last step was accepted (or at the start), and fit_model then reads the
  // residuals and the Jacobian at the optimum. Those points are answered from the last few
  // evaluations (bit-identical points, so the same residuals); each still counts as one.
  int operator()(const InputType& theta, ValueType& residuals) const {
    ++evaluations_;
    if (reuse_evaluations_) {
      if (const ValueType* kept = recent_.find(theta)) {
        residuals = *kept;
        return 0;
      }
    }
    simulate(theta, residuals);
    if (reuse_evaluations_) recent_.keep(theta, residuals);
    return 0;
  }

  // Forward differences with steps relative to each unknown's typical size (1 in solver
  // coordinates): parameters that start at zero still get a meaningful step.
  int df(const InputType& theta, JacobianType& jacobian) const {
    ValueType base(values());
    (*this)(theta, base);
    ValueType shifted(values());
    for (int j = 0; j < theta.size(); ++j) {
      InputType t = theta;
      const double h = 1e-5 * std::max(std::abs(theta[j]), 1.0);
      t[j] += h;
      // A shifted point is not asked for again: not kept.
      ++evaluations_;
      if (j >= first_effect_ && starts_late_[static_cast<std::size_t>(j - first_effect_)]) {
        shifted_after_onset(t, base, shifted);
      } else {
        simulate(t, shifted);
      }
      jacobian.col(j) = (shifted - base) / h;
    }
    return 0;
  }

  int evaluations() const { return evaluations_; }
  double scale(int i) const { return scales_[i]; }

 private:
  void simulate(const InputType& theta, ValueType& residuals) const {
    predictor_.residuals(
        model(theta), segments_,
        std::span<double>(residuals.data(), static_cast<std::size_t>(residuals.size())));
  }

  // The residuals at `theta`, which differs from the point of `base` only in a parameter of an
  // effect that starts inside the capture: a segment that ends before the onset runs the model
  // without the effect throughout (SegmentPredictor::run), so its residuals are base's, bit
  // for bit, and only the later segments are simulated (the onset check's forward selection
  // spends 40 % of its time in such fits).
  void shifted_after_onset(const InputType& theta, const ValueType& base,
                           ValueType& shifted) const {
    shifted = base;
    predictor_.residuals(model(theta), later_, later_residuals_);
    std::size_t from = 0;
    for (std::size_t i = 0; i < later_.size(); ++i) {
      const std::size_t count = SegmentPredictor::residual_count({&later_[i], 1});
      std::copy_n(later_residuals_.begin() + static_cast<std::ptrdiff_t>(from), count,
                  shifted.data() + later_offsets_[i]);
      from += count;
    }
  }

  // Per effect parameter: does it act only from an onset on (EffectCandidate::apply puts a
  // part with onset_s > 0 into the model's `effects` alone, not into `before`)?
  static void collect_late(const EffectCandidate& c, std::vector<bool>& out) {
    if (c.parts.empty()) {
      out.insert(out.end(), c.parameters.size(), c.onset_s > 0.0);
      return;
    }
    for (const auto& part : c.parts) collect_late(part, out);
  }
  const SegmentPredictor& predictor_;
  std::span<const Segment> segments_;
  const EffectCandidate* candidate_;
  Calibration start_;
  Scales scales_;
  int calibration_slot_[kCalibrationCount] = {-1, -1, -1, -1};
  int first_effect_ = 0;
  bool reuse_evaluations_ = true;
  std::vector<bool> starts_late_;  // per effect parameter (collect_late)
  // The segments that reach the onset (when a parameter starts late), their offsets in the
  // residuals, and shifted_after_onset's room for their residuals.
  std::vector<Segment> later_;
  std::vector<std::size_t> later_offsets_;
  mutable std::vector<double> later_residuals_;
  // The accepted point and the rejected trials after it.
  mutable RecentResults<InputType, ValueType, 4> recent_;
  mutable int evaluations_ = 0;
};

// Where a calibrated value sits within `tolerance` of the bound interval's width from a bound:
// -1 on the lower, +1 on the upper, 0 inside.
int bound_side(double solver_value, int i, double tolerance) {
  const double margin = tolerance * (kUpper[i] - kLower[i]);
  if (solver_value <= kLower[i] + margin) return -1;
  if (solver_value >= kUpper[i] - margin) return 1;
  return 0;
}

constexpr double kBoundTolerance = 0.002;  // calibration_at_bound's default

// The standard error of calibrated value `index` held on its bound, from the profile of the
// fitting cost: the value pinned at trial steps inward from the bound (about threefold from
// 0.3 % of the bound interval to all of it), every other unknown refitted. The clamp that holds
// a value on its bound has no gradient, so Gauss-Newton gave it an error of zero, and the drift
// test then found any difference to it "significant" (seed 796000: the named model's b 58.1 +-
// 1.4 early, 30.0 +- 0 on its bound late, z 20). The profile's rise is fitted as g d + c d^2
// (weighted by the rise's own size, so that the short steps count as much as the long ones),
// and the error is where its curvature alone raises the cost by `rise` (one residual variance
// in the sum of squares), as Gauss-Newton's error does for an interior value (whose gradient
// is zero): how well the data pin the value, not how hard they push it against the bound. A
// profile without upward curvature does not pin it: the bound interval's width.
double profile_error(const SegmentPredictor& predictor, std::span<const Segment> segments,
                     const EffectCandidate* candidate, const FitResult& fit, int index, int side,
                     double rise, const FitSettings& settings) {
  FitSettings pinned = settings;
  pinned.uncertainties = false;
  // Each refit starts at the fit's optimum, a short way off: a few solver steps reach it.
  pinned.max_iterations = std::min(settings.max_iterations, 5);
  pinned.free_calibration[static_cast<std::size_t>(index)] = false;
  // The effect's parameters start where the fit left them (their solver coordinates are
  // relative to `initial`).
  std::optional<EffectCandidate> warm;
  if (candidate) {
    warm = *candidate;
    for (std::size_t k = 0; k < warm->parameters.size() && k < fit.values.size(); ++k) {
      warm->parameters[k].initial = fit.values[k];
    }
  }
  const EffectCandidate* refitted = warm ? &*warm : nullptr;
  const auto [lower, upper] = calibration_bounds(settings.stated);
  const auto member = [index](Calibration& c) -> double& { return calibration_value(c, index); };
  Calibration low = lower, high = upper;
  const double width = member(high) - member(low);
  if (!(rise > 0.0)) return width;
  const double at_bound = side < 0 ? member(low) : member(high);
  const auto cost_at = [&](double inward) {
    Calibration c = fit.parameters.calibration;
    member(c) = at_bound - side * inward;
    return fit_model(predictor, segments, refitted, c, pinned).cost;
  };
  // The fit's own optimum may be less converged than a refit from it: the lower of the two.
  const double base = std::min(fit.cost, cost_at(0.0));
  // Weighted least squares of r = g d + c d^2 (d in the interval's widths, r in `rise`s).
  double s11 = 0.0, s12 = 0.0, s22 = 0.0, b1 = 0.0, b2 = 0.0;
  for (const double share : {0.003, 0.01, 0.03, 0.1, 0.3, 1.0}) {
    const double r = (cost_at(share * width) - base) / rise;
    const double w = 1.0 / std::max(r * r, 1.0);
    s11 += w * share * share;
    s12 += w * share * share * share;
    s22 += w * share * share * share * share;
    b1 += w * share * r;
    b2 += w * share * share * r;
  }
  const double det = s11 * s22 - s12 * s12;
  const double curvature = det > 0.0 ? (s11 * b2 - s12 * b1) / det : 0.0;
  if (!(curvature > 1.0)) return width;
  return width / std::sqrt(curvature);
}

}  // namespace

FitResult fit_model(const SegmentPredictor& predictor, std::span<const Segment> segments,
                    const EffectCandidate* candidate, const Calibration& start,
                    const FitSettings& settings) {
  SegmentFitProblem problem(predictor, segments, candidate, start, settings.free_calibration,
                            settings.stated, settings.reuse_evaluations,
                            settings.skip_segments_before_onset);
  Eigen::VectorXd theta = problem.start_point();
  Eigen::LevenbergMarquardt<SegmentFitProblem> solver(problem);
  solver.setMaxfev(settings.max_iterations);
  solver.setXtol(1e-5);
  solver.setFtol(1e-6);
  solver.minimize(theta);

  FitResult result;
  result.parameters = problem.model(theta);
  result.values = problem.effect_values(theta);
  Eigen::VectorXd residuals(problem.values());
  problem(theta, residuals);
  result.cost = residuals.squaredNorm() / static_cast<double>(residuals.size());

  if (settings.uncertainties) {
    // Gauss-Newton covariance s^2 (J^T J)^-1. The residuals of one segment are correlated, so
    // these errors are optimistic; they rank how well the data pin each parameter down.
    Eigen::MatrixXd jacobian(problem.values(), problem.inputs());
    problem.df(theta, jacobian);
    const double dof = std::max<double>(1.0, residuals.size() - theta.size());
    const double s2 = residuals.squaredNorm() / dof;
    const Eigen::MatrixXd info = jacobian.transpose() * jacobian;
    const Eigen::MatrixXd cov = s2 * info.completeOrthogonalDecomposition().pseudoInverse();
    const auto err = [&](int j) { return std::sqrt(std::max(cov(j, j), 0.0)); };
    for (int i = 0; i < kCalibrationCount; ++i) {
      const int slot = problem.calibration_slot(i);
      if (slot < 0) {
        calibration_value(result.calibration_errors, i) = 0.0;
        continue;
      }
      const int side =
          bound_side(std::clamp(theta[slot], kLower[i], kUpper[i]), i, kBoundTolerance);
      calibration_value(result.calibration_errors, i) =
          side == 0 ? err(slot) * problem.scale(i)
                    : profile_error(predictor, segments, candidate, result, i, side,
                                    s2 / static_cast<double>(residuals.size()), settings);
    }
    if (candidate) {
      for (std::size_t i = 0; i < candidate->parameters.size(); ++i) {
        result.value_errors.push_back(err(problem.first_effect() + static_cast<int>(i)) *
                                      candidate->parameters[i].scale);
      }
    }
  }
  result.evaluations = problem.evaluations();
  return result;
}

Calibration best_beta_on_grid(const SegmentPredictor& predictor, std::span<const Segment> segments,
                              const Calibration& start, const Calibration& stated,
                              double relative_step) {
  const auto [lower, upper] = calibration_bounds(stated);
  std::vector<double> residuals(SegmentPredictor::residual_count(segments));
  ModelParameters p;
  p.calibration = start;
  Calibration best = start;
  double best_cost = std::numeric_limits<double>::infinity();
  for (double beta = lower.beta; beta <= upper.beta; beta *= 1.0 + relative_step) {
    p.calibration.beta = beta;
    predictor.residuals(p, segments, residuals);
    double cost = 0.0;
    for (const double r : residuals) cost += r * r;
    if (cost < best_cost) {
      best_cost = cost;
      best.beta = beta;
    }
  }
  return best;
}

std::vector<std::string> calibration_at_bound(const Calibration& c, const Calibration& stated,
                                              double tolerance) {
  const Scales scales(stated);
  const double values[kCalibrationCount] = {c.beta, c.Kv, c.m, c.b};
  const char* names[kCalibrationCount] = {"beta", "Kv", "m", "b"};
  std::vector<std::string> out;
  for (int i = 0; i < kCalibrationCount; ++i) {
    if (bound_side(values[i] / scales[i], i, tolerance) != 0) out.emplace_back(names[i]);
  }
  return out;
}

Calibration within_bounds(const Calibration& c, const Calibration& stated) {
  // A tenth of the way in from a bound: the solver then has room in both directions.
  const Scales scales(stated);
  const auto inside = [&](double v, int i) {
    const double margin = 0.1 * (kUpper[i] - kLower[i]);
    return std::clamp(v / scales[i], kLower[i] + margin, kUpper[i] - margin) * scales[i];
  };
  return {inside(c.beta, 0), inside(c.Kv, 1), inside(c.m, 2), inside(c.b, 3)};
}

std::pair<Calibration, Calibration> calibration_bounds(const Calibration& stated) {
  const Scales s(stated);
  return {{kLower[0] * s[0], kLower[1] * s[1], kLower[2] * s[2], kLower[3] * s[3]},
          {kUpper[0] * s[0], kUpper[1] * s[1], kUpper[2] * s[2], kUpper[3] * s[3]}};
}

}  // namespace leakmon::model
