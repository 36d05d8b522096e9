#include "detect/drift_reference.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace leakmon::detect {

DriftReference::DriftReference(const DriftReferenceOptions& options)
    : options_(options),
      blocks_(static_cast<std::size_t>(std::ceil(options.keep_seconds / options.block_seconds)) +
              2) {}

// Weighted least squares of residual = scale (a + b (t_k - t)) over the window: a is the
// reference now. Sums in slot order (the results are reproducible to the bit).
double DriftReference::reference(double t, double block_sigma, bool level_only,
                                 double anchored_until) const {
  const double window = options_.window_seconds;
  if (!(window > 0.0) && std::isnan(anchored_until)) return 0.0;
  double newest = t - options_.guard_seconds;
  if (!std::isnan(anchored_until)) newest = std::max(newest, anchored_until);
  // The time the line is carried to: now, or a guard beyond blocks that stopped.
  double now = t;
  double oldest = t - options_.guard_seconds - window;
  if (options_.hold_across_gaps && window > 0.0) {
    double last = -std::numeric_limits<double>::infinity();
    for (const Block& b : blocks_.stored()) {
      if (b.t <= newest) last = std::max(last, b.t);
    }
    if (std::isfinite(last) && last < newest - options_.guard_seconds) {
      now = last + (t - newest);
      newest = last;
      oldest = last - window;
    }
  }
  // w = scale^2; sums of w, w tau, w tau^2, residual scale, residual scale tau.
  double w = 0.0, wt = 0.0, wtt = 0.0, wy = 0.0, wyt = 0.0, earliest = t, latest = oldest;
  std::size_t n = 0;
  for (const Block& b : blocks_.stored()) {
    if (b.t > newest || (b.t < oldest && window > 0.0)) continue;
    const double tau = b.t - now, weight = b.scale * b.scale;
    w += weight;
    wt += weight * tau;
    wtt += weight * tau * tau;
    wy += b.residual * b.scale;
    wyt += b.residual * b.scale * tau;
    earliest = std::min(earliest, b.t);
    latest = std::max(latest, b.t);
    ++n;
  }
  if (n < kLevelBlocks || !(w > 0.0)) return 0.0;
  const double level = wy / w;  // at the window's weighted centre
  if (n < kSlopeBlocks || !(window > 0.0) || level_only ||
      (options_.slope_needs_full_window &&
       (options_.hold_across_gaps ? latest : newest) - earliest < 0.9 * window)) {
    return level;
  }
  const double det = w * wtt - wt * wt;
  if (!(det > 0.0)) return level;
  double extrapolated;
  if (options_.shrink_slope) {
    // Slope of the line and its variance (blocks with the learned spread).
    const double slope = (w * wyt - wt * wy) / det;
    const double slope_variance = block_sigma * block_sigma * w / det;
    const double shrink = slope * slope / (slope * slope + slope_variance);
    extrapolated = level - shrink * slope * (wt / w);
  } else {
    extrapolated = (wy * wtt - wyt * wt) / det;  // the line at tau = 0
  }
  return level + std::clamp(extrapolated - level, -options_.bound, options_.bound);
}

void DriftReference::save(DetectorState& state, std::string_view prefix) const {
  save_ring(state, prefix, blocks_, kBlockFields);
}

void DriftReference::restore(const DetectorState& state, std::string_view prefix) {
  restore_ring(state, prefix, blocks_, kBlockFields);
}

}  // namespace leakmon::detect
