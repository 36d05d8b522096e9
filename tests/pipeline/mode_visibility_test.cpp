// A rig whose hydraulic mode does not show in the chamber pressures: ModeVisibilityCheck on its
// own, and through replay_capture, where seal friction (MODEL.md's coulomb_friction) leaves the
// pressure-only detectors nothing to see a leak by. The daemon must say so at the end of learning
// and again after a restart, and say nothing of the kind on a healthy rig.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "pipeline/mode_visibility.hpp"
#include "pipeline/replay.hpp"
#include "pipeline/state_store.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/capture_slices.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::pipeline {
namespace {

TEST(ModeVisibilityCheck, NoiseFloorIsTheTransducersNoiseWithItsQuantisation) {
  EXPECT_NEAR(ModeVisibilityCheck::noise_floor_pa(5e3, 20.7e6 / 4096.0), 5208.5, 0.1);
  EXPECT_DOUBLE_EQ(ModeVisibilityCheck::noise_floor_pa(3e3, 0.0), 3e3);
}

TEST(ModeVisibilityCheck, MedianRatioWithinABinAndGapsNotCounted) {
  ModeVisibilityCheck check(5e3);
  EXPECT_TRUE(std::isnan(check.median_ratio()));
  std::mt19937 rng(3);
  std::lognormal_distribution<double> index(std::log(3.0 * 5e3), 0.4);
  for (int i = 0; i < 2000; ++i) {
    check.add(index(rng));
    check.add(std::nan(""));
  }
  EXPECT_EQ(check.count(), 2000u);
  // The median of the log-normal is 3 x the floor; a bin is 6 % wide.
  EXPECT_NEAR(check.median_ratio(), 3.0, 0.2);
  // Far outside the bins: clamped to the end bins, still counted.
  ModeVisibilityCheck extremes(5e3);
  extremes.add(1.0);
  EXPECT_LT(extremes.median_ratio(), 0.6);
  extremes.add(1e9);
  extremes.add(1e9);
  EXPECT_GT(extremes.median_ratio(), 100.0);
}

// A pressure-only capture (t, p1, p2) of MODEL.md's rig, seal friction F_C [N] (0: none).
capture::Capture pressure_capture(double friction, double seconds, unsigned seed) {
  sim::Scenario scenario = sim::preset("healthy", seed);
  scenario.duration_s = seconds;
  if (friction > 0.0) {
    const sim::EffectParameter params[] = {{"F_C", friction}};
    scenario.effects.enable("coulomb_friction", params);
  }
  return test::columns_of(sim::simulate(scenario), {"t", "p1", "p2"});
}

std::vector<io::Event> blind_events(const ReplayResult& result) {
  std::vector<io::Event> out;
  std::copy_if(result.events.begin(), result.events.end(), std::back_inserter(out),
               [](const io::Event& e) { return e.kind == io::EventKind::detection_blind; });
  return out;
}

TEST(ModeVisibilityReplay, SealFrictionIsAnnouncedAtTheEndOfLearningAndAfterARestart) {
  const capture::Capture stuck = pressure_capture(80.0, 240.0, 7);
  const DaemonConfig config = default_replay_config(stuck);
  const ReplayResult result = replay_capture(stuck, config);
  const auto blind = blind_events(result);
  ASSERT_EQ(blind.size(), 1u);
  // Once, when the detector has learned (its learning period and the features' first window).
  EXPECT_GT(blind.front().t, 60.0);
  EXPECT_LT(blind.front().t, 150.0);
  EXPECT_EQ(blind.front().actuator, "actuator");
  EXPECT_NE(blind.front().message.find("hydraulic mode"), std::string::npos);
  ASSERT_EQ(result.actuators.size(), 1u);
  EXPECT_TRUE(result.actuators.front().detection_blind);
  EXPECT_LT(result.actuators.front().mode_visibility, ModeVisibilityCheck::kBlindRatio);
  EXPECT_GT(result.actuators.front().mode_visibility, 1.0);
  for (const auto& e : result.events) {
    EXPECT_FALSE(e.kind == io::EventKind::alarm_raised && e.alarm == "internal_leakage");
  }

  // A restart keeps the verdict of the learning period and says it again.
  ReplayOptions options;
  options.state_directory = test::scratch_dir("mode_visibility_restart");
  replay_capture(stuck, config, options);
  const ReplayResult resumed = replay_capture(pressure_capture(80.0, 30.0, 8), config, options);
  const auto again = blind_events(resumed);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_LT(again.front().t, 30.0);  // at its first decision, not after learning anew
  ASSERT_EQ(resumed.learned.size(), 1u);
  EXPECT_NEAR(resumed.learned.front().healthy_index_ratio, result.actuators.front().mode_visibility,
              1e-9);
}

// A restart in the middle of learning: the verdict comes when the resumed learning ends.
TEST(ModeVisibilityReplay, ARestartWhileLearningIsJudgedWhenLearningEnds) {
  const capture::Capture stuck = pressure_capture(80.0, 240.0, 9);
  const DaemonConfig config = default_replay_config(stuck);
  ReplayOptions options;
  options.state_directory = test::scratch_dir("mode_visibility_restart_while_learning");
  const ReplayResult before = replay_capture(test::rows_between(stuck, 0.0, 40.0), config, options);
  const ReplayResult after = replay_capture(test::rows_between(stuck, 40.0, 1e9), config, options);
  EXPECT_TRUE(blind_events(before).empty());
  ASSERT_EQ(before.learned.size(), 1u);
  EXPECT_TRUE(std::isnan(before.learned.front().healthy_index_ratio));
  EXPECT_EQ(blind_events(after).size(), 1u);
  ASSERT_EQ(after.actuators.size(), 1u);
  EXPECT_TRUE(after.actuators.front().detection_blind);
}

TEST(ModeVisibilityReplay, AHealthyRigIsNotBlindAndTheFlowBalanceIsNotJudged) {
  const capture::Capture healthy = pressure_capture(0.0, 200.0, 7);
  const ReplayResult result = replay_capture(healthy, default_replay_config(healthy));
  EXPECT_TRUE(blind_events(result).empty());
  ASSERT_EQ(result.actuators.size(), 1u);
  EXPECT_FALSE(result.actuators.front().detection_blind);
  // MODEL.md's nominal rig: the mode stands about six times above the transducer's noise.
  EXPECT_GT(result.actuators.front().mode_visibility, 4.0);

  // With u and x the flow balance decides; it does not need the mode, friction or not.
  sim::Scenario scenario = sim::preset("healthy", 7);
  scenario.duration_s = 200.0;
  const sim::EffectParameter params[] = {{"F_C", 80.0}};
  scenario.effects.enable("coulomb_friction", params);
  const capture::Capture full = sim::simulate(scenario);
  const ReplayResult flow = replay_capture(full, default_replay_config(full));
  EXPECT_TRUE(blind_events(flow).empty());
  ASSERT_EQ(flow.actuators.size(), 1u);
  EXPECT_TRUE(std::isnan(flow.actuators.front().mode_visibility));
}

// The checksum line of a state file, as state_store.cpp forms it (FNV-1a, 64 bit, hex).
std::string with_checksum(const std::string& body) {
  std::uint64_t hash = 1469598103934665603ull;
  for (unsigned char c : body) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  return body + "checksum " + hex + "\n";
}

// The verdict round-trips; a file of format 1 (written before it existed) still loads and leaves
// the rig unjudged.
TEST(ModeVisibilityState, TheVerdictRoundTripsAndFormatOneFilesStillLoad) {
  ActuatorState state;
  state.actuator = "cylinder";
  state.fingerprint.hash = "0123456789abcdef";
  state.detector = detect::DetectorState("index_cusum", 1);
  state.detector.put("learned", 1.0);
  state.healthy_index_ratio = 1.6339;
  const std::string text = encode_state(state);
  EXPECT_NE(text.find("healthy_index_ratio 1.6339"), std::string::npos);
  EXPECT_DOUBLE_EQ(decode_state(text).healthy_index_ratio, 1.6339);

  state.healthy_index_ratio = std::nan("");
  std::string unjudged = encode_state(state);
  EXPECT_EQ(unjudged.find("healthy_index_ratio"), std::string::npos);
  ASSERT_EQ(unjudged.rfind("leakmon-state 2\n", 0), 0u);
  std::string format_one = "leakmon-state 1\n" + unjudged.substr(unjudged.find('\n') + 1);
  format_one = with_checksum(format_one.substr(0, format_one.rfind("checksum ")));
  const ActuatorState old = decode_state(format_one);
  EXPECT_EQ(old.actuator, "cylinder");
  EXPECT_TRUE(std::isnan(old.healthy_index_ratio));
  // And a file from a newer format is refused by name.
  std::string newer = "leakmon-state 3\n" + unjudged.substr(unjudged.find('\n') + 1);
  newer = with_checksum(newer.substr(0, newer.rfind("checksum ")));
  EXPECT_THROW(decode_state(newer), detect::StateError);
}

}  // namespace
}  // namespace leakmon::pipeline
