#include "detect/supply_tracker.hpp"

#include <limits>

namespace leakmon::detect {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

SupplyTracker::SupplyTracker(const SupplyTrackerOptions& options)
    : options_(options), memory_(std::exp(-options.reading_seconds / kSupplyMemorySeconds)) {}

void SupplyTracker::reset() {
  estimate_ = anchor_ = step_time_ = kNaN;
  off_readings_ = 0;
}

void SupplyTracker::resume_after_gap() {
  step_time_ = kNaN;
  off_readings_ = 0;
}

bool SupplyTracker::add(double t, double reading, bool direct) {
  if (std::isnan(reading)) return false;
  const double step = kSupplyStepShare * options_.configured;
  // A direct reading is the supply (no memory).
  const double memory = direct ? 0.0 : memory_;
  if (options_.rule == SupplyTrackerOptions::StepRule::jump) {
    if (std::isnan(estimate_) || std::abs(reading - estimate_) > step) {
      const bool stepped = !std::isnan(estimate_);
      if (stepped) step_time_ = t;
      estimate_ = reading;
      return stepped;
    }
    estimate_ = memory * estimate_ + (1.0 - memory) * reading;
    return false;
  }
  if (std::isnan(estimate_)) {
    estimate_ = anchor_ = reading;
  } else if (!direct && std::abs(reading - estimate_) > step) {
    if (++off_readings_ >= options_.confirm_readings) {
      estimate_ = reading;
      off_readings_ = 0;
    }
  } else {
    off_readings_ = 0;
    estimate_ = memory * estimate_ + (1.0 - memory) * reading;
  }
  if (std::abs(estimate_ - anchor_) > step) {
    anchor_ = estimate_;
    step_time_ = t;
    return true;
  }
  return false;
}

void SupplyTracker::set_after_step(double t, double supply) {
  estimate_ = anchor_ = supply;
  step_time_ = t;
}

void SupplyTracker::save(DetectorState& state, std::string_view prefix) const {
  state.put(state_key(prefix, "estimate"), estimate_);
  state.put(state_key(prefix, "anchor"), anchor_);
  state.put(state_key(prefix, "step_time"), step_time_);
  state.put_count(state_key(prefix, "off_readings"), off_readings_);
}

void SupplyTracker::restore(const DetectorState& state, std::string_view prefix) {
  estimate_ = state.get(state_key(prefix, "estimate"));
  anchor_ = state.get(state_key(prefix, "anchor"));
  step_time_ = state.get(state_key(prefix, "step_time"));
  off_readings_ = state.get_count(state_key(prefix, "off_readings"));
}

}  // namespace leakmon::detect
