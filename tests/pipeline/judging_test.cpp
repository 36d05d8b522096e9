// Issue 23: a shift that starts with a 5-minute hold, then steps, a sine block and steps again
// (sim/scenarios/hold-300-steps-sine.yaml), through the daemon's own pipeline with u and x and the
// default detector (flow_law, the flow balance in motion). It must not learn the healthy valve
// from the hold's single load (the at-rest balance raised false internal_leakage alarms then),
// must say while it does not judge (the hold: not_judged / judging_resumed events), and judges
// the sine block as it judges the steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "pipeline/replay.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/capture_slices.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::pipeline {
namespace {

constexpr double kStepsStart = 300.0, kSineStart = 600.0;

const capture::Capture& shift() {
  static const capture::Capture capture = sim::simulate(
      sim::load_scenario(test::source_dir() + "/sim/scenarios/hold-300-steps-sine.yaml"));
  return capture;
}

std::vector<io::Event> of_kind(const std::vector<io::Event>& events, io::EventKind kind) {
  std::vector<io::Event> out;
  std::copy_if(events.begin(), events.end(), std::back_inserter(out),
               [kind](const io::Event& e) { return e.kind == kind; });
  return out;
}

DaemonConfig announcing_after(double seconds) {
  DaemonConfig config = default_replay_config(shift());
  config.actuators.front().alarm.not_judged_event_seconds = seconds;
  return config;
}

TEST(Judging, AHoldThenStepsAndASineRaisesNoFalseLeakAndSaysWhenItDoesNotJudge) {
  const ReplayResult result = replay_capture(shift(), announcing_after(120.0));
  for (const auto& e : of_kind(result.events, io::EventKind::alarm_raised)) {
    ADD_FAILURE() << "false alarm " << e.alarm << " at t " << e.t;
  }
  const auto not_judged = of_kind(result.events, io::EventKind::not_judged);
  const auto resumed = of_kind(result.events, io::EventKind::judging_resumed);
  ASSERT_EQ(not_judged.size(), 1u);
  ASSERT_EQ(resumed.size(), 1u);
  // The hold: learning waits for loads to learn from, announced before the steps begin.
  EXPECT_EQ(not_judged[0].reason, "waiting_for_excitation");
  EXPECT_LT(not_judged[0].t, kStepsStart);
  EXPECT_LT(not_judged[0].not_judged_since, not_judged[0].t - 119.0);
  // Learned on the steps (their rests), it judges there, and through the sine block: the flow
  // law holds in motion.
  EXPECT_GT(resumed[0].t, kStepsStart);
  EXPECT_LT(resumed[0].t, kSineStart);
  const ActuatorStatus& status = result.actuators.front();
  EXPECT_TRUE(status.judged);
  EXPECT_EQ(status.not_judged_reason, detect::NotJudgedReason::none);
  ASSERT_GT(status.decided_seconds, 1100.0);
  // The share counts the hold and the learning as not judged, and the sine as judged.
  const double share = status.judged_seconds / status.decided_seconds;
  EXPECT_GT(share, (status.decided_seconds - resumed[0].t - 60.0) / status.decided_seconds);
  EXPECT_LT(share, (status.decided_seconds - kStepsStart) / status.decided_seconds);
}

// With the default announcement time (600 s) the 5-minute hold passes silently: the status says
// it, the event log stays quiet.
TEST(Judging, ShorterSpellsThanTheEventTimeStayOutOfTheEventLog) {
  const ReplayResult result = replay_capture(shift(), default_replay_config(shift()));
  EXPECT_TRUE(of_kind(result.events, io::EventKind::not_judged).empty());
  EXPECT_TRUE(of_kind(result.events, io::EventKind::judging_resumed).empty());
  // Cut in the hold: the status names it.
  const ReplayResult in_hold = replay_capture(test::rows_between(shift(), 0.0, kStepsStart - 50.0),
                                              default_replay_config(shift()));
  const ActuatorStatus& status = in_hold.actuators.front();
  EXPECT_FALSE(status.judged);
  EXPECT_EQ(status.not_judged_reason, detect::NotJudgedReason::waiting_for_excitation);
  EXPECT_LT(status.not_judged_since, 1.0);
  EXPECT_TRUE(of_kind(in_hold.events, io::EventKind::not_judged).empty());
}

// A hold, a long 0.5 Hz sine and only then the steps (sim/scenarios/hold-sine-steps.yaml): the
// hold (one load) is not learned from; the sine's motion identifies the load term (the at-rest
// balance had to wait for the steps), and the model learned on it judges the steps after it
// without a false alarm.
TEST(Judging, AHoldAndASineThenStepsAreLearnedOnTheStepsAloneWithoutAFalseLeak) {
  constexpr double kSineBegin = 103.0, kStepsBegin = 627.0;
  const capture::Capture capture =
      sim::simulate(sim::load_scenario(test::source_dir() + "/sim/scenarios/hold-sine-steps.yaml"));
  const ReplayResult result = replay_capture(capture, default_replay_config(capture));
  for (const auto& e : of_kind(result.events, io::EventKind::alarm_raised)) {
    ADD_FAILURE() << "false alarm " << e.alarm << " at t " << e.t;
  }
  const ActuatorStatus& status = result.actuators.front();
  EXPECT_TRUE(status.judged);
  EXPECT_EQ(status.not_judged_reason, detect::NotJudgedReason::none);
  // Learned within the sine, and judged from then on, the steps included.
  const double steps_seconds = status.decided_seconds - kStepsBegin;
  EXPECT_GT(status.judged_seconds, steps_seconds + 0.5 * (kStepsBegin - kSineBegin));
  EXPECT_LT(status.judged_seconds, status.decided_seconds - kSineBegin);
}

}  // namespace
}  // namespace leakmon::pipeline
