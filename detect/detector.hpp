// The plug-in point between features and alarms. The worker builds one Observation per hop
// (every `step` samples) for each actuator; a Detector turns the stream of observations into a
// score that the alarm state machine (daemon/) compares with its raise/clear thresholds.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "detect/detector_state.hpp"
#include "detect/learned_change.hpp"

namespace leakmon::detect {

inline constexpr double kMissing = std::numeric_limits<double>::quiet_NaN();

// What one hop of an actuator's data says. Any field the configuration does not acquire, or
// whose window held a gap, is NaN.
struct Observation {
  double t = kMissing;         // time of the sample that completed the window [s]
  double index_p1 = kMissing;  // db8 level-2 detail RMS of p1 over the window [Pa]
  double index_p2 = kMissing;  // the same for p2 [Pa]
  // Means over the last hop (the `step` newest samples):
  double u = kMissing;   // valve command [V]
  double x = kMissing;   // position [m]
  double p1 = kMissing;  // chamber pressures [Pa]
  double p2 = kMissing;
  double ps = kMissing;    // supply pressure [Pa], where the rig has that transducer
  double temp = kMissing;  // oil temperature [degC], where the rig has that transducer
  // Standard deviation of the position reference or position over the window, when known: the
  // excitation that produced the index.
  double x_activity = kMissing;
  // The hop's chamber pressure samples themselves (the `step` samples the hop means average,
  // oldest first, NaN where one was missing; empty when the chamber is not acquired), for
  // detectors that compute their own features. Valid only during the update() call.
  std::span<const double> p1_samples, p2_samples;
  // The hop's command and position samples the same way (empty when not acquired), for
  // detectors that integrate the flow balance in motion.
  std::span<const double> u_samples, x_samples;
};

// Why a detector is not judging: it cannot see a leak right now, whatever the score says (the
// score holds). Unlike detection_blind (the rig, permanently), these pass when the operation or
// the data changes.
enum class NotJudgedReason {
  none,                    // judging
  learning,                // learning the healthy baseline
  waiting_for_excitation,  // learning is over but the data has too few distinct loads at rest
  cannot_learn,            // waited max_excitation_wait_seconds for them in vain: nothing learned
  in_motion,               // no block at rest lately (sine, sweep, triangle)
  no_load,                 // at rest near |p1 - p2| = 0: a leak's flow C_L (p1 - p2) vanishes
  outside_learned_loads,   // at rest at a load the learning data never covered
  supply_settling,         // the supply pressure is still moving after a step
  no_excitation,           // pressure-only: the index is far below its learned level (a hold)
  outside_learned_regime,  // pressure-only: the program excites the mode unlike any learned one
  data_gap,                // the observations lack a signal the detector needs
  sensor_fault,            // a channel is faulty or suspect: the detector is not fed
  detection_blind,         // pressure-only: the rig's hydraulic mode does not show (the daemon's)
};

// The names the daemon uses for the reasons (/status, metrics labels, events), in enum order.
inline constexpr std::array<std::string_view, 13> kNotJudgedReasonNames = {"none",
                                                                           "learning",
                                                                           "waiting_for_excitation",
                                                                           "cannot_learn",
                                                                           "in_motion",
                                                                           "no_load",
                                                                           "outside_learned_loads",
                                                                           "supply_settling",
                                                                           "no_excitation",
                                                                           "outside_learned_regime",
                                                                           "data_gap",
                                                                           "sensor_fault",
                                                                           "detection_blind"};

constexpr std::string_view to_string(NotJudgedReason reason) {
  return kNotJudgedReasonNames[static_cast<std::size_t>(reason)];
}

struct Decision {
  // Dimensionless evidence of a leak: the alarm raises when score >= raise_threshold() and
  // clears when score <= clear_threshold(). NaN when the detector cannot judge this hop (still
  // learning, or the observation had gaps): the alarm state then holds.
  double score = kMissing;
  bool learning = true;  // still learning the healthy baseline
  // While learning: the hops until the baseline is learned (settling included), for operators
  // ("learning, 23 s left"); NaN when not learning or not known.
  double learning_hops_left = kMissing;
  double baseline = kMissing;  // learned healthy level of the index [Pa]
  double index = kMissing;     // the index value this decision used [Pa]
  // Estimated internal leakage coefficient C_L [m^3/(s Pa)] and its 95 % half-width; NaN when
  // the detector cannot size the leak.
  double leak_coefficient = kMissing;
  double leak_coefficient_ci = kMissing;
  // nu(40 degC) / nu(T) at the oil temperature of this hop when the detector knows it (the
  // leak coefficient is then stated at 40 degC and flows r C_L (p1 - p2) now); NaN otherwise.
  double viscosity_ratio = kMissing;
  // Whether this decision could have revealed a leak, and why not (none when judged). A
  // detector that does not say otherwise judges whenever it has learned and has a score.
  bool judged = false;
  NotJudgedReason not_judged_reason = NotJudgedReason::learning;
  // Sets judged / not_judged_reason from `learning` and the score, for detectors without more
  // to say.
  void judge_by_score() {
    judged = !learning && !std::isnan(score);
    not_judged_reason = judged ? NotJudgedReason::none
                               : (learning ? NotJudgedReason::learning : NotJudgedReason::data_gap);
  }
};

class Detector {
 public:
  virtual ~Detector() = default;
  virtual std::string_view name() const = 0;
  // Called once per hop from the worker thread; must not block.
  virtual Decision update(const Observation& observation) = 0;
  // Thresholds on Decision::score that this detector was designed for; the alarm configuration
  // may override them. clear_threshold() < raise_threshold() gives the deadband.
  virtual double raise_threshold() const = 0;
  virtual double clear_threshold() const = 0;
  // Forget everything learned (e.g. after maintenance, on operator request).
  virtual void reset() = 0;
  // Everything the detector has learned and where it stands in its current block and test, so
  // that a restart resumes instead of relearning (a leak that opened while the daemon was down
  // would otherwise be learned as healthy). A detector of the same kind and options that
  // imports the state decides exactly as this one would have on the same following data.
  virtual DetectorState export_state() const = 0;
  // Throws StateError when `state` does not fit this detector (other kind or layout, sizes that
  // do not match its options); the detector is then reset(). Not for the real-time path: it
  // allocates.
  virtual void import_state(const DetectorState& state) = 0;
  // After import_state() on a restart: the data resumes after a gap of unknown length, on a
  // source clock that may have started over. Forgets what is tied to times or to the previous
  // hop (what was learned stays).
  virtual void resume_after_gap() {}
  // Source time [s] from a fresh start (or reset()) to its first decision: what it ignores as
  // start-up transient plus what it learns from. NaN when the detector cannot say.
  virtual double learning_seconds() const { return std::numeric_limits<double>::quiet_NaN(); }
  // Whether it sees a leak only through the hydraulic mode in the chamber pressures (the ~75 Hz
  // resonance the level-2 details cover): then a rig whose mode does not show above the
  // transducers' noise gives it nothing to see, and the daemon says so
  // (pipeline/mode_visibility.hpp).
  virtual bool needs_hydraulic_mode() const { return false; }
  // Once learning is over: a step of alarm-worthy size the detector's own feature made while it
  // learned (learned_change.hpp), which it has taken for healthy. Detectors that do not look
  // return nothing; the actuator monitor probes the index of pressure-only ones itself.
  virtual std::optional<LearnedChange> learned_change() const { return std::nullopt; }
};

}  // namespace leakmon::detect
