// Replay of simulated captures through the daemon's pipeline: an alarm after a clear leak's
// onset and none before; none on healthy captures of other seeds and either controller. The
// captures are made here with sim::, from MODEL.md's presets.
#include "pipeline/replay.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>

#include "sim/scenario.hpp"
#include "sim/simulate.hpp"

namespace leakmon::pipeline {
namespace {

using capture::Role;

constexpr double kOnset = 120.0;

capture::Capture leaking_capture(std::uint64_t seed, std::string_view preset) {
  sim::Scenario scenario = sim::preset(preset, seed);
  scenario.duration_s = kOnset + 60.0;
  sim::InternalLeakage leak;
  leak.C_L = 2.5e-12;  // 0.15 l/min/MPa, the paper's size range
  leak.onset_s = kOnset;
  scenario.effects.internal_leakage = leak;
  return sim::simulate(scenario);
}

capture::Capture healthy_capture(std::uint64_t seed, std::string_view preset, double duration) {
  sim::Scenario scenario = sim::preset(preset, seed);
  scenario.duration_s = duration;
  scenario.effects.internal_leakage.reset();
  return sim::simulate(scenario);
}

std::vector<io::Event> raised(const ReplayResult& result) {
  std::vector<io::Event> out;
  std::copy_if(result.events.begin(), result.events.end(), std::back_inserter(out),
               [](const io::Event& e) { return e.kind == io::EventKind::alarm_raised; });
  return out;
}

TEST(Replay, DefaultConfigUsesTheKnownColumnsPresent) {
  capture::Capture capture;
  capture.path = "in-memory";
  capture.columns = {"t", "p1", "x", "q_int"};
  capture.values = {{0.0, 0.002, 0.004}, {1.0, 2.0, 3.0}, {0, 0, 0}, {0, 0, 0}};
  const DaemonConfig config = default_replay_config(capture);
  ASSERT_EQ(config.actuators.size(), 1u);
  const auto& actuator = config.actuators.front();
  EXPECT_EQ(actuator.channels[Role::p1].channel, "p1");
  EXPECT_EQ(actuator.channels[Role::x].channel, "x");
  EXPECT_FALSE(actuator.channels[Role::p2].present());
  EXPECT_FALSE(actuator.channels[Role::u].present());
  EXPECT_EQ(config.groups.front().period_ns, 2'000'000);
  EXPECT_EQ(actuator.features.window, 400u);
  EXPECT_EQ(actuator.features.step, 20u);

  capture.columns = {"t", "p2"};
  capture.values = {{0.0, 0.002}, {1.0, 2.0}};
  EXPECT_THROW(default_replay_config(capture), capture::CaptureError);
}

TEST(Replay, EverySampleReachesTheWorkerAndOneDecisionPerHop) {
  const capture::Capture capture = healthy_capture(3, "healthy", 10.0);
  const auto result = replay_capture(capture, default_replay_config(capture));
  EXPECT_EQ(result.samples_read, capture.rows());
  EXPECT_EQ(result.samples_processed, capture.rows());
  EXPECT_EQ(result.ring_drops, 0u);
  ASSERT_EQ(result.actuators.size(), 1u);
  // The index runs SensorPlausibility::kDelay samples behind (spike rejection), so the last
  // kDelay rows never reach a window.
  const std::size_t fed = capture.rows() - detect::SensorPlausibility::kDelay;
  EXPECT_EQ(result.actuators[0].decisions + result.actuators[0].suspended_decisions,
            (fed - 400) / 20 + 1);
  EXPECT_EQ(result.actuators[0].suspended_decisions, 0u) << "a healthy capture held the detector";
  EXPECT_GT(result.actuators[0].index_p1, 0.0);
}

TEST(Replay, AlarmAfterLeakOnsetAndNoneBefore) {
  const capture::Capture capture = leaking_capture(11, "healthy");
  const auto result = replay_capture(capture, default_replay_config(capture));
  const auto alarms = raised(result);
  ASSERT_FALSE(alarms.empty()) << "no alarm for a 0.15 l/min/MPa leak";
  EXPECT_GT(alarms.front().t, kOnset) << "alarm before the leak started";
  EXPECT_LT(alarms.front().t, kOnset + 60.0);
  EXPECT_EQ(alarms.front().alarm, "internal_leakage");
  EXPECT_EQ(alarms.front().channel, "p1");
  EXPECT_TRUE(std::isfinite(alarms.front().index));
}

TEST(Replay, NoAlarmOnHealthyCapturesOfEitherController) {
  for (auto [preset, seed] : {std::pair{"healthy", 21u}, std::pair{"healthy-ft", 22u}}) {
    const capture::Capture capture = healthy_capture(seed, preset, 180.0);
    const auto result = replay_capture(capture, default_replay_config(capture));
    EXPECT_TRUE(raised(result).empty())
        << preset << " seed " << seed << ": false alarm at t=" << raised(result).front().t;
  }
}

TEST(Replay, TwoThreadsAtOnceGiveTheSameEventsAsOne) {
  const capture::Capture capture = leaking_capture(12, "healthy-ft");
  const auto config = default_replay_config(capture);
  const auto alone = replay_capture(capture, config);
  ReplayResult a, b;
  std::thread first([&] { a = replay_capture(capture, config); });
  std::thread second([&] { b = replay_capture(capture, config); });
  first.join();
  second.join();
  ASSERT_EQ(a.events.size(), alone.events.size());
  ASSERT_EQ(b.events.size(), alone.events.size());
  for (std::size_t i = 0; i < alone.events.size(); ++i) {
    EXPECT_EQ(a.events[i].t, alone.events[i].t);
    EXPECT_EQ(b.events[i].t, alone.events[i].t);
  }
}

}  // namespace
}  // namespace leakmon::pipeline

namespace leakmon::pipeline {
namespace {

// The flow balance in motion gets its per-sample command and position from the pipeline
// (Observation::u_samples, x_samples): replayed, it learns on the steps and finds a leak that
// opens during a sine, where the detectors that judge only at rest see nothing.
TEST(Replay, FlowLawFindsALeakOpeningInASine) {
  sim::Scenario scenario;
  scenario.controller = sim::ControllerKind::fault_tolerant;
  scenario.seed = 4;
  scenario.duration_s = 180.0;
  sim::Phase steps, sine;
  steps.duration_s = 110.0;
  sine.kind = sim::PhaseKind::sine;
  sine.F = 1.5;
  sine.A = 0.02;
  scenario.program = {steps, sine};
  sim::InternalLeakage leak;
  leak.C_L = 1e-12;
  leak.onset_s = 140.0;
  scenario.effects.internal_leakage = leak;
  const capture::Capture capture = sim::simulate(scenario);
  DaemonConfig config = default_replay_config(capture);
  config.actuators.at(0).detector = "flow_law";
  const auto result = replay_capture(capture, config);
  const auto alarms = raised(result);
  ASSERT_EQ(alarms.size(), 1u);
  EXPECT_GT(alarms[0].t, leak.onset_s);
  EXPECT_LT(alarms[0].t, leak.onset_s + 10.0);
  EXPECT_NEAR(alarms[0].leak_coefficient, 1e-12, 0.2e-12);
  EXPECT_FALSE(result.actuators.at(0).learning);
}

}  // namespace
}  // namespace leakmon::pipeline
