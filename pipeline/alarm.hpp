// One alarm's state machine in the manner of ISA-18.2: separate raise and clear thresholds
// (the deadband between them stops chattering), an on-delay (the condition must hold that long
// before the alarm annunciates) and an off-delay (the return must hold that long before it
// clears), and optional latching (a latched alarm stays annunciated after the condition returns
// to normal, until an operator acknowledges it). Times are source times in seconds.
#pragma once

#include <cmath>
#include <string_view>

namespace leakmon::pipeline {

struct AlarmSettings {
  double raise_threshold = 1.0;  // score >= this counts towards raising
  double clear_threshold = 0.5;  // score <= this counts towards clearing (< raise_threshold)
  double on_delay_s = 0.0;
  double off_delay_s = 0.0;
  bool latching = false;
  // A detector not judging for longer than this [s] is announced (event not_judged).
  double not_judged_event_seconds = 600.0;
};

enum class AlarmState {
  normal,                  // condition normal, nothing to acknowledge
  active_unacknowledged,   // condition in alarm, operator not yet acknowledged
  active_acknowledged,     // condition in alarm, acknowledged
  returned_unacknowledged  // latched: condition back to normal, waiting for acknowledgement
};

std::string_view to_string(AlarmState state);

// What an update or acknowledgement changed, for the event stream.
struct AlarmTransition {
  bool raised = false;
  bool cleared = false;
  bool acknowledged = false;
  bool any() const { return raised || cleared || acknowledged; }
};

class Alarm {
 public:
  explicit Alarm(const AlarmSettings& settings);

  // One decision at source time t. A NaN score (detector cannot judge) holds the state and
  // restarts neither delay.
  AlarmTransition update(double score, double t);
  // Operator acknowledgement. A latched alarm whose condition has returned clears here.
  AlarmTransition acknowledge();

  AlarmState state() const { return state_; }
  // Annunciated: what an operator's panel shows (active, or latched and not yet acknowledged).
  bool active() const { return state_ != AlarmState::normal; }
  bool condition() const { return condition_; }
  const AlarmSettings& settings() const { return settings_; }
  // New thresholds and delays keep the current state (a reload must not drop an active alarm).
  void set_settings(const AlarmSettings& settings) { settings_ = settings; }
  // A restart: the annunciated state and the condition come back (an unacknowledged latched
  // alarm must still wait for its operator); the delays start over.
  void restore(AlarmState state, bool condition) {
    state_ = state;
    condition_ = condition;
    above_since_ = below_since_ = NAN;
  }

 private:
  AlarmSettings settings_;
  AlarmState state_ = AlarmState::normal;
  bool condition_ = false;    // the delayed, deadbanded condition
  double above_since_ = NAN;  // first time of the current run of score >= raise
  double below_since_ = NAN;  // first time of the current run of score <= clear
};

}  // namespace leakmon::pipeline
