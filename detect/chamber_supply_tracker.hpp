// The supply pressure as one chamber's transducer sees it, for a rig with neither a `ps` channel
// nor the other chamber. At rest with a critically lapped valve p1 + p2 = ps + pt and
// p1 - p2 = K_s x / A (the spring load), so one chamber rests at (ps + pt) / 2 +- K_s x / (2 A):
// its hold levels form two clusters, mirrored around mid-supply (the reference programme's
// levels are +-a around a stationary mean, MODEL.md). Learning fixes their geometry (the
// spread of |level - mid|); afterwards a hold level that fits neither cluster is a supply step
// (or ramp), and the new mid-supply is read from the two clusters of the holds after it.
// Only shifts of mid-supply against the learned one are reported: a transducer offset or an
// asymmetric programme cancels.
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

#include "detect/detector.hpp"
#include "detect/ring.hpp"

namespace leakmon::detect {

class ChamberSupplyTracker {
 public:
  enum class Event { none, step, estimated };
  // `capacity` holds are kept: enough for the learning period (holds last 0.5-4 s).
  explicit ChamberSupplyTracker(std::size_t capacity = 128);

  // One hop: the chamber's mean pressure and whether the load rested over the hop. `step` when
  // a hold level fits neither cluster (the step began after step_time()); `estimated` when the
  // holds after a step gave the new mid-supply.
  Event add(double t, double pressure, bool still);
  // At the end of learning: the clusters of the holds seen so far. False (and inactive) when
  // they are not two clusters clearly apart, e.g. a programme that rests on one side only.
  bool learn();
  bool active() const { return !std::isnan(learned_mid_); }
  // A step was seen and its new level is not yet known.
  bool awaiting() const { return !std::isnan(awaiting_since_); }
  // The latest step began after this: the end of the last hold that fitted the old clusters
  // (when the new level is estimated, the last that fits the old clusters but not the new).
  double step_time() const { return step_time_; }
  // Mid-supply now minus mid-supply at learning [Pa]: half the supply's change.
  double mid_shift() const { return active() ? mid_ - learned_mid_ : 0.0; }

  void reset();
  // The data resumes on another clock: holds and times are forgotten, the geometry stays.
  void resume_after_gap();
  // Everything under `prefix.` (DetectorState); restore() throws StateError on a mismatch.
  void save(DetectorState& state, std::string_view prefix) const;
  void restore(const DetectorState& state, std::string_view prefix);

 private:
  struct Hold {
    double t, level;
  };
  static constexpr std::array<RecordField<Hold>, 2> kHoldFields = {
      record_field<&Hold::t>("t"), record_field<&Hold::level>("level")};
  struct Clusters {
    bool ok = false;
    double mid = kMissing;
  };
  void finish_hold();
  void on_hold(const Hold& hold);
  bool fits(double level, double mid) const;
  // The two clusters of the holds ending after `since`, each with at least `min_per_side`.
  Clusters clusters_since(double since, std::size_t min_per_side);

  Ring<Hold> holds_;
  std::vector<double> scratch_;  // sorting buffer, sized at construction
  // The hold being formed.
  std::size_t still_hops_ = 0, used_hops_ = 0;
  double sum_ = 0.0;
  double last_t_ = kMissing, hold_start_ = kMissing;
  // Learned geometry: mid-supply and the range of |level - mid|.
  double learned_mid_ = kMissing, near_ = kMissing, far_ = kMissing;
  double learned_offset_ = kMissing;  // mean level - mid at learning (an asymmetric programme)
  double mid_ = kMissing;
  double last_fit_t_ = kMissing;       // end of the newest hold that fitted
  double step_time_ = kMissing;        // the latest step began after this
  double awaiting_since_ = kMissing;   // holds ending after this estimate the new level
  double awaiting_from_t_ = kMissing;  // when the step was seen (for the give-up fallback)
  Event pending_ = Event::none;
};

}  // namespace leakmon::detect
