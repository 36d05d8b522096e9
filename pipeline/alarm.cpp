#include "pipeline/alarm.hpp"

namespace leakmon::pipeline {

std::string_view to_string(AlarmState state) {
  switch (state) {
    case AlarmState::normal:
      return "normal";
    case AlarmState::active_unacknowledged:
      return "active_unacknowledged";
    case AlarmState::active_acknowledged:
      return "active_acknowledged";
    case AlarmState::returned_unacknowledged:
      return "returned_unacknowledged";
  }
  return "unknown";
}

Alarm::Alarm(const AlarmSettings& settings) : settings_(settings) {}

AlarmTransition Alarm::update(double score, double t) {
  AlarmTransition transition;
  if (std::isnan(score)) return transition;

  above_since_ =
      score >= settings_.raise_threshold ? (std::isnan(above_since_) ? t : above_since_) : NAN;
  below_since_ =
      score <= settings_.clear_threshold ? (std::isnan(below_since_) ? t : below_since_) : NAN;
  if (!condition_ && !std::isnan(above_since_) && t - above_since_ >= settings_.on_delay_s) {
    condition_ = true;
  } else if (condition_ && !std::isnan(below_since_) && t - below_since_ >= settings_.off_delay_s) {
    condition_ = false;
  }

  switch (state_) {
    case AlarmState::normal:
      if (condition_) {
        state_ = AlarmState::active_unacknowledged;
        transition.raised = true;
      }
      break;
    case AlarmState::active_unacknowledged:
      if (!condition_) {
        state_ = settings_.latching ? AlarmState::returned_unacknowledged : AlarmState::normal;
        transition.cleared = !settings_.latching;
      }
      break;
    case AlarmState::active_acknowledged:
      if (!condition_) {
        state_ = AlarmState::normal;
        transition.cleared = true;
      }
      break;
    case AlarmState::returned_unacknowledged:
      // Still annunciated; the condition coming back changes nothing the operator sees.
      if (condition_) state_ = AlarmState::active_unacknowledged;
      break;
  }
  return transition;
}

AlarmTransition Alarm::acknowledge() {
  AlarmTransition transition;
  switch (state_) {
    case AlarmState::normal:
    case AlarmState::active_acknowledged:
      break;
    case AlarmState::active_unacknowledged:
      state_ = AlarmState::active_acknowledged;
      transition.acknowledged = true;
      break;
    case AlarmState::returned_unacknowledged:
      state_ = AlarmState::normal;
      transition.acknowledged = true;
      transition.cleared = true;
      break;
  }
  return transition;
}

}  // namespace leakmon::pipeline
