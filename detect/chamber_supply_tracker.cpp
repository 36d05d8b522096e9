#include "detect/chamber_supply_tracker.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::detect {

namespace {

// A hold's first this long is the end of the move (the hydraulic mode and the controller
// settling), not its rest level; a hold shorter than kHoldMinSeconds after that is not used.
constexpr double kHoldSettleSeconds = 0.2;
constexpr double kHoldMinSeconds = 0.2;
// Holds per cluster that fix the geometry at learning, and the new level after a step (a
// cluster's mean is then within about 0.46 MPa / sqrt(3) of the truth on the paper's
// programme: about 1 % of the supply).
constexpr std::size_t kLearnPerSide = 4;
constexpr std::size_t kStepPerSide = 3;
// A hold fits a cluster within this share of the learned spread of |level - mid| (plus the
// transducer's noise): the learning period's extremes lie inside the programme's range by a
// share of about 1 / holds.
constexpr double kFitShare = 0.2;
constexpr double kFitPressure = 30e3;
// A step whose new level cannot be read from two clusters by then (the programme rested on one
// side only): the level from the holds' mean, the learned asymmetry removed.
constexpr double kGiveUpSeconds = 120.0;

}  // namespace

ChamberSupplyTracker::ChamberSupplyTracker(std::size_t capacity)
    : holds_(std::max<std::size_t>(capacity, 2 * kLearnPerSide)), scratch_(holds_.capacity()) {}

void ChamberSupplyTracker::reset() {
  holds_.clear();
  still_hops_ = used_hops_ = 0;
  sum_ = 0.0;
  last_t_ = hold_start_ = kMissing;
  learned_mid_ = near_ = far_ = learned_offset_ = mid_ = kMissing;
  last_fit_t_ = step_time_ = awaiting_since_ = awaiting_from_t_ = kMissing;
  pending_ = Event::none;
}

void ChamberSupplyTracker::resume_after_gap() {
  holds_.clear();
  still_hops_ = used_hops_ = 0;
  sum_ = 0.0;
  last_t_ = hold_start_ = kMissing;
  last_fit_t_ = step_time_ = kMissing;
  // A step seen before the gap still needs its level: from the holds after the gap.
  if (awaiting()) awaiting_since_ = awaiting_from_t_ = -1e300;
}

ChamberSupplyTracker::Event ChamberSupplyTracker::add(double t, double pressure, bool still) {
  pending_ = Event::none;
  if (std::isnan(pressure) || !still) {
    finish_hold();
  } else {
    if (still_hops_ == 0) hold_start_ = t;
    ++still_hops_;
    if (t - hold_start_ >= kHoldSettleSeconds) {
      sum_ += pressure;
      ++used_hops_;
      last_t_ = t;
    }
  }
  return pending_;
}

void ChamberSupplyTracker::finish_hold() {
  const bool long_enough =
      used_hops_ > 0 && last_t_ - hold_start_ >= kHoldSettleSeconds + kHoldMinSeconds;
  const Hold hold{last_t_, used_hops_ > 0 ? sum_ / static_cast<double>(used_hops_) : 0.0};
  still_hops_ = used_hops_ = 0;
  sum_ = 0.0;
  if (long_enough) on_hold(hold);
}

bool ChamberSupplyTracker::fits(double level, double mid) const {
  const double tolerance = kFitShare * (far_ - near_) + kFitPressure;
  const double d = std::abs(level - mid);
  return d >= near_ - tolerance && d <= far_ + tolerance;
}

void ChamberSupplyTracker::on_hold(const Hold& hold) {
  holds_.push(hold);
  if (!active()) return;
  if (!awaiting()) {
    if (fits(hold.level, mid_)) {
      last_fit_t_ = hold.t;
      return;
    }
    // The step began after the last hold that fitted (the ramp broke the hold it fell in).
    step_time_ = std::isnan(last_fit_t_) ? hold.t : last_fit_t_;
    awaiting_since_ = step_time_;
    awaiting_from_t_ = hold.t;
    pending_ = Event::step;
    return;
  }
  // Awaiting the new level: two clusters of the holds since the step, each hold fitting them.
  // A hold that does not (the ramp's end, a second step) moves the window past it.
  const double old_mid = mid_;
  for (;;) {
    const Clusters c = clusters_since(awaiting_since_, kStepPerSide);
    if (c.ok) {
      mid_ = c.mid;
      break;
    }
    if (std::isnan(c.mid)) {
      if (hold.t - awaiting_from_t_ < kGiveUpSeconds) return;
      double sum = 0.0;
      std::size_t n = 0;
      for (std::size_t age = 0; age < holds_.size() && holds_.newest(age).t > awaiting_since_;
           ++age) {
        sum += holds_.newest(age).level;
        ++n;
      }
      if (n == 0) return;
      mid_ = sum / static_cast<double>(n) - learned_offset_;
      break;
    }
    // Misfit: drop the oldest hold of the window.
    double oldest = hold.t;
    for (std::size_t age = 0; age < holds_.size() && holds_.newest(age).t > awaiting_since_;
         ++age) {
      oldest = holds_.newest(age).t;
    }
    awaiting_since_ = oldest;
  }
  // Holds after the step that happened to fit the old clusters too moved step_time() past the
  // step; it began after the newest hold (before it was seen) that fits the old clusters only.
  for (std::size_t age = 0; age < holds_.size(); ++age) {
    const Hold& h = holds_.newest(age);
    if (h.t > awaiting_from_t_) continue;
    if (h.t <= step_time_ - kGiveUpSeconds) break;
    if (fits(h.level, old_mid) && !fits(h.level, mid_)) {
      step_time_ = std::min(step_time_, h.t);
      break;
    }
  }
  awaiting_since_ = awaiting_from_t_ = kMissing;
  last_fit_t_ = hold.t;
  pending_ = Event::estimated;
}

// Largest gap of the sorted levels splits the two clusters; mid is halfway between their
// means (the programme's levels are symmetric in distribution, not in count). Not ok with
// mid NaN: too few holds; not ok with mid set: a hold does not fit (after learning).
ChamberSupplyTracker::Clusters ChamberSupplyTracker::clusters_since(double since,
                                                                    std::size_t min_per_side) {
  std::size_t n = 0;
  for (std::size_t age = 0; age < holds_.size() && holds_.newest(age).t > since; ++age) {
    scratch_[n++] = holds_.newest(age).level;
  }
  Clusters c;
  if (n < 2 * min_per_side) return c;
  std::sort(scratch_.begin(), scratch_.begin() + static_cast<std::ptrdiff_t>(n));
  std::size_t split = 0;  // the gap after scratch_[split]
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (scratch_[i + 1] - scratch_[i] > scratch_[split + 1] - scratch_[split]) split = i;
  }
  const std::size_t lower = split + 1;
  if (lower < min_per_side || n - lower < min_per_side) return c;
  double sum_lower = 0.0, sum_upper = 0.0;
  for (std::size_t i = 0; i < n; ++i) (i < lower ? sum_lower : sum_upper) += scratch_[i];
  c.mid =
      0.5 * (sum_lower / static_cast<double>(lower) + sum_upper / static_cast<double>(n - lower));
  c.ok = true;
  if (active()) {
    for (std::size_t i = 0; i < n; ++i) c.ok = c.ok && fits(scratch_[i], c.mid);
  }
  return c;
}

bool ChamberSupplyTracker::learn() {
  learned_mid_ = kMissing;
  const Clusters c = clusters_since(-1e300, kLearnPerSide);
  if (!c.ok) return false;
  double near = 1e300, far = 0.0, sum = 0.0;
  for (std::size_t age = 0; age < holds_.size(); ++age) {
    const double d = std::abs(holds_.newest(age).level - c.mid);
    near = std::min(near, d);
    far = std::max(far, d);
    sum += holds_.newest(age).level;
  }
  // Two clusters clearly apart: the gap between them (2 near) wider than either.
  if (!(2.0 * near > far - near)) return false;
  learned_mid_ = mid_ = c.mid;
  near_ = near;
  far_ = far;
  learned_offset_ = sum / static_cast<double>(holds_.size()) - c.mid;
  last_fit_t_ = holds_.newest(0).t;
  return true;
}

void ChamberSupplyTracker::save(DetectorState& state, std::string_view prefix) const {
  save_ring(state, state_key(prefix, "holds"), holds_, kHoldFields);
  const auto key = [&](std::string_view name) { return state_key(prefix, name); };
  state.put_count(key("hold.still_hops"), still_hops_);
  state.put_count(key("hold.used_hops"), used_hops_);
  state.put(key("hold.sum"), sum_);
  state.put(key("hold.last_t"), last_t_);
  state.put(key("hold.start"), hold_start_);
  state.put(key("learned_mid"), learned_mid_);
  state.put(key("near"), near_);
  state.put(key("far"), far_);
  state.put(key("learned_offset"), learned_offset_);
  state.put(key("mid"), mid_);
  state.put(key("last_fit_t"), last_fit_t_);
  state.put(key("step_time"), step_time_);
  state.put(key("awaiting_since"), awaiting_since_);
  state.put(key("awaiting_from_t"), awaiting_from_t_);
  state.put_count(key("pending"), static_cast<std::size_t>(pending_));
}

void ChamberSupplyTracker::restore(const DetectorState& state, std::string_view prefix) {
  restore_ring(state, state_key(prefix, "holds"), holds_, kHoldFields);
  const auto key = [&](std::string_view name) { return state_key(prefix, name); };
  still_hops_ = state.get_count(key("hold.still_hops"));
  used_hops_ = state.get_count(key("hold.used_hops"));
  if (used_hops_ > still_hops_) throw StateError("chamber supply: more used hops than still ones");
  sum_ = state.get(key("hold.sum"));
  last_t_ = state.get(key("hold.last_t"));
  hold_start_ = state.get(key("hold.start"));
  learned_mid_ = state.get(key("learned_mid"));
  near_ = state.get(key("near"));
  far_ = state.get(key("far"));
  learned_offset_ = state.get(key("learned_offset"));
  mid_ = state.get(key("mid"));
  last_fit_t_ = state.get(key("last_fit_t"));
  step_time_ = state.get(key("step_time"));
  awaiting_since_ = state.get(key("awaiting_since"));
  awaiting_from_t_ = state.get(key("awaiting_from_t"));
  const std::size_t pending = state.get_count(key("pending"));
  if (pending > static_cast<std::size_t>(Event::estimated)) {
    throw StateError("chamber supply: unknown pending event");
  }
  pending_ = static_cast<Event>(pending);
}

}  // namespace leakmon::detect
