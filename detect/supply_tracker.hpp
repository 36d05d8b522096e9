// The supply pressure a detector normalises by, from readings: a `ps` transducer (direct), or
// the chambers at rest, where the valve's lands balance and p1 + p2 = ps + pt (MODEL.md). The
// estimate follows the readings with a short memory; a change of more than kSupplyStepShare of
// the configured supply is a step: the chambers follow it within about a second, so the hops
// in the kSupplyTransientSeconds after it are not used (settled()), and what was learned
// against the old supply may need re-anchoring (the caller's business: add() says so).
//
// The two step rules the detectors were measured with:
// - jump (flow_balance): a reading that far from the estimate is a step at once, and the
//   estimate jumps to it.
// - drift_from_anchor (the feature test): a rest reading that far from the estimate has to
//   persist for `confirm_readings` readings (not one odd hop); the step is when the estimate
//   has moved that far from the supply at the last step (the anchor), so a ramp is a step too.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <string_view>

#include "detect/detector_state.hpp"

namespace leakmon::detect {

// A step of the supply: this share of the configured supply.
inline constexpr double kSupplyStepShare = 0.02;
// Hops this long after a step are not used.
inline constexpr double kSupplyTransientSeconds = 3.0;
// Memory of the estimate from rest readings between steps.
inline constexpr double kSupplyMemorySeconds = 2.0;

struct SupplyTrackerOptions {
  enum class StepRule { jump, drift_from_anchor };
  double configured = 0.0;  // the configured supply [Pa]: the estimate until a reading
  StepRule rule = StepRule::jump;
  std::size_t confirm_readings = 1;  // drift_from_anchor: rest readings that make a step
  double reading_seconds = 0.04;     // time between readings (sets the memory per reading)
};

class SupplyTracker {
 public:
  explicit SupplyTracker(const SupplyTrackerOptions& options);

  // A reading at t (NaN: none this hop); `direct` for a `ps` transducer. True when it made a
  // step (step_time() is then t).
  bool add(double t, double reading, bool direct);
  // A new supply found otherwise (one chamber's hold levels): estimate and anchor, a step at t.
  void set_after_step(double t, double supply);

  // The supply to use [Pa]: the estimate, or the configured supply before any reading.
  double estimate() const { return std::isnan(estimate_) ? options_.configured : estimate_; }
  bool has_reading() const { return !std::isnan(estimate_); }
  double step_time() const { return step_time_; }  // the last step, NaN when none
  // No step within kSupplyTransientSeconds before t.
  bool settled(double t) const {
    return std::isnan(step_time_) || t - step_time_ >= kSupplyTransientSeconds;
  }

  void reset();
  // The data resumes on another clock: the step time is forgotten, the estimate stays.
  void resume_after_gap();

  // `prefix.{estimate,anchor,step_time,off_readings}`.
  void save(DetectorState& state, std::string_view prefix) const;
  void restore(const DetectorState& state, std::string_view prefix);

 private:
  SupplyTrackerOptions options_;
  double memory_;  // of the estimate per rest reading
  double estimate_ = std::numeric_limits<double>::quiet_NaN();
  double anchor_ = std::numeric_limits<double>::quiet_NaN();  // drift_from_anchor: at the last step
  double step_time_ = std::numeric_limits<double>::quiet_NaN();
  std::size_t off_readings_ = 0;  // consecutive rest readings far from the estimate
};

}  // namespace leakmon::detect
