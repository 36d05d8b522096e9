// sim/scenarios/morning-start.yaml through the daemon's own pipeline: everything a real rig does
// at 6 a.m. at once (cold oil warming up, a worn rig with seal friction and a biased valve, a
// flaky p2 cable, a frozen p1, a position dropout, a supply change), a restart half way, and a
// 2e-12 leak at the end. With u and x: every fault named on its channel and nothing else before
// the leak, the leak found, across the restart too. With p1 and p2 only: no alarm can come (the
// friction leaves no hydraulic mode), and the daemon says so once, not as a false leak or a
// driver fault.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "pipeline/replay.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/capture_slices.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::pipeline {
namespace {

constexpr double kOnset = 1000.0;

const capture::Capture& morning() {
  static const capture::Capture capture =
      sim::simulate(sim::load_scenario(test::source_dir() + "/sim/scenarios/morning-start.yaml"));
  return capture;
}

std::vector<double> leak_alarm_times(const std::vector<io::Event>& events) {
  std::vector<double> out;
  for (const auto& e : events) {
    if (e.kind == io::EventKind::alarm_raised && e.alarm == "internal_leakage") out.push_back(e.t);
  }
  return out;
}

std::set<std::string> sensor_faults(const std::vector<io::Event>& events) {
  std::set<std::string> out;
  for (const auto& e : events) {
    if (e.kind == io::EventKind::alarm_raised && e.alarm == "sensor_fault") {
      out.insert(e.channel + " " + e.fault);
    }
  }
  return out;
}

bool has(const std::vector<io::Event>& events, io::EventKind kind) {
  return std::any_of(events.begin(), events.end(),
                     [kind](const io::Event& e) { return e.kind == kind; });
}

const std::set<std::string> kFaults = {"p2 spikes", "p1 frozen", "x dropout"};

TEST(MorningStart, EveryChannelNamesItsFaultAndOnlyTheLeakIsALeak) {
  const ReplayResult result = replay_capture(morning(), default_replay_config(morning()));
  EXPECT_EQ(sensor_faults(result.events), kFaults);
  EXPECT_FALSE(has(result.events, io::EventKind::driver_fault));
  EXPECT_FALSE(has(result.events, io::EventKind::detection_blind));  // the flow balance decides
  const auto alarms = leak_alarm_times(result.events);
  ASSERT_FALSE(alarms.empty());
  EXPECT_GE(alarms.front(), kOnset);
  EXPECT_LT(alarms.front(), kOnset + 30.0);
}

TEST(MorningStart, ARestartHalfWayKeepsWhatWasLearnedAndStillFindsTheLeak) {
  ReplayOptions options;
  options.state_directory = test::scratch_dir("morning_start_restart");
  const DaemonConfig config = default_replay_config(morning());
  // Down from 520 s to 540 s, in the middle of the warm-up.
  const ReplayResult before =
      replay_capture(test::rows_between(morning(), 0.0, 520.0), config, options);
  const ReplayResult after =
      replay_capture(test::rows_between(morning(), 540.0, 1e9), config, options);
  EXPECT_TRUE(leak_alarm_times(before.events).empty());
  EXPECT_TRUE(has(after.events, io::EventKind::state_restored));
  const auto alarms = leak_alarm_times(after.events);
  ASSERT_FALSE(alarms.empty());
  EXPECT_GE(alarms.front(), kOnset);
  EXPECT_LT(alarms.front(), kOnset + 30.0);
  EXPECT_FALSE(has(after.events, io::EventKind::driver_fault));
}

// `detector: flow_law` (the flow balance in motion, with `temp` and `ps`): the valve's bias,
// learned cold, raised internal_leakage some 50 times from 278 s on before it had a regressor
// of its own (docs/detection.md); now only the leak is a leak.
TEST(MorningStart, FlowLawRaisesOnlyTheLeak) {
  DaemonConfig config = default_replay_config(morning());
  config.actuators.at(0).detector = "flow_law";
  const ReplayResult result = replay_capture(morning(), config);
  EXPECT_EQ(sensor_faults(result.events), kFaults);
  const auto alarms = leak_alarm_times(result.events);
  ASSERT_FALSE(alarms.empty());
  EXPECT_GE(alarms.front(), kOnset);
  EXPECT_LT(alarms.front(), kOnset + 30.0);
}

TEST(MorningStart, PressuresOnlySayTheyCannotSeeALeakInsteadOfStayingSilent) {
  const capture::Capture pressures = test::columns_of(morning(), {"t", "p1", "p2"});
  const ReplayResult result = replay_capture(pressures, default_replay_config(pressures));
  EXPECT_TRUE(leak_alarm_times(result.events).empty());
  EXPECT_FALSE(has(result.events, io::EventKind::driver_fault));
  EXPECT_EQ(sensor_faults(result.events), (std::set<std::string>{"p2 spikes", "p1 frozen"}));
  const auto blind = std::count_if(result.events.begin(), result.events.end(), [](const auto& e) {
    return e.kind == io::EventKind::detection_blind;
  });
  EXPECT_EQ(blind, 1);
  ASSERT_EQ(result.actuators.size(), 1u);
  EXPECT_TRUE(result.actuators.front().detection_blind);
}

}  // namespace
}  // namespace leakmon::pipeline
