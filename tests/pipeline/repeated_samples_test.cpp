// An acquisition that hands the worker the same sample twice (a device polled faster than it
// updates): RepeatedSampleCheck on its own, and through replay_capture, where such a stream made
// the pressure-only detector raise a false leak alarm before the check held its decision.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "pipeline/repeated_samples.hpp"
#include "pipeline/replay.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/capture_slices.hpp"

namespace leakmon::pipeline {
namespace {

constexpr double kLsb = 5.05e3;  // 12-bit pressure transducer, MODEL.md

// Two quantised pressures at rest with one LSB of noise: the quietest healthy stream.
std::vector<std::array<double, 2>> quiet_pressures(std::size_t samples, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kLsb);
  std::vector<std::array<double, 2>> out(samples);
  for (auto& s : out) {
    s[0] = std::round((11e6 + noise(rng)) / kLsb) * kLsb;
    s[1] = std::round((6e6 + noise(rng)) / kLsb) * kLsb;
  }
  return out;
}

TEST(RepeatedSampleCheck, AQuietHealthyStreamIsNeverRepeating) {
  RepeatedSampleCheck check;
  std::size_t most = 0;
  for (const auto& s : quiet_pressures(60 * 500, 3)) {
    EXPECT_FALSE(check.push(s));
    most = std::max(most, check.repeats());
  }
  // Both readings repeat by chance about one sample in ten: far below the raise count.
  EXPECT_GT(most, 20u);
  EXPECT_LT(most, RepeatedSampleCheck::kRaise * 3 / 4);
}

TEST(RepeatedSampleCheck, EveryOtherSampleHeldIsRepeatingWithinASecondAndClearsAfter) {
  RepeatedSampleCheck check;
  const auto stream = quiet_pressures(20 * 500, 4);
  std::size_t raised_at = 0, cleared_at = 0;
  for (std::size_t i = 0; i < stream.size(); ++i) {
    // 5-10 s: a device that updates at 250 Hz, polled at 500 Hz.
    const bool held = i >= 5 * 500 && i < 10 * 500 && i % 2 == 1;
    const bool repeating = check.push(held ? stream[i - 1] : stream[i]);
    if (repeating && raised_at == 0) raised_at = i;
    if (!repeating && raised_at != 0 && cleared_at == 0) cleared_at = i;
  }
  ASSERT_GT(raised_at, 0u);
  EXPECT_GE(raised_at, 5u * 500);
  EXPECT_LT(raised_at, 6u * 500);
  ASSERT_GT(cleared_at, 0u);
  EXPECT_GE(cleared_at, 10u * 500);
  EXPECT_LT(cleared_at, 11u * 500);
}

TEST(RepeatedSampleCheck, OneChannelAloneIsNotJudgedAndGapsAreNoRepeats) {
  RepeatedSampleCheck one;
  const std::array<double, 1> constant{1e6};
  for (int i = 0; i < 2000; ++i) EXPECT_FALSE(one.push(constant));
  RepeatedSampleCheck gaps;
  const std::array<double, 2> missing{NAN, NAN};
  for (int i = 0; i < 2000; ++i) EXPECT_FALSE(gaps.push(missing));
  EXPECT_EQ(gaps.repeats(), 0u);
}

// A healthy pressure-only rig whose acquisition starts to deliver every sample twice at 200 s.
TEST(RepeatedSamplesReplay, AHeldStreamHoldsTheDecisionInsteadOfRaisingALeak) {
  sim::Scenario scenario = sim::preset("healthy", 5);
  scenario.duration_s = 400.0;
  capture::Capture pressures = test::columns_of(sim::simulate(scenario), {"t", "p1", "p2"});
  capture::Capture held = pressures;
  for (const char* name : {"p1", "p2"}) {
    auto& v = held.column(name);
    for (std::size_t i = 200 * 500 + 1; i < v.size(); i += 2) v[i] = v[i - 1];
  }

  const ReplayResult clean = replay_capture(pressures, default_replay_config(pressures));
  const ReplayResult result = replay_capture(held, default_replay_config(held));
  for (const auto* r : {&clean, &result}) {
    for (const auto& e : r->events)
      EXPECT_FALSE(e.kind == io::EventKind::alarm_raised && e.alarm == "internal_leakage")
          << "t " << e.t;
  }
  std::vector<io::Event> faults;
  std::copy_if(result.events.begin(), result.events.end(), std::back_inserter(faults),
               [](const io::Event& e) { return e.kind == io::EventKind::driver_fault; });
  ASSERT_EQ(faults.size(), 1u);
  EXPECT_GE(faults.front().t, 200.0);
  EXPECT_LT(faults.front().t, 202.0);
  EXPECT_NE(faults.front().message.find("repeat"), std::string::npos) << faults.front().message;
  EXPECT_TRUE(std::none_of(clean.events.begin(), clean.events.end(), [](const io::Event& e) {
    return e.kind == io::EventKind::driver_fault;
  }));
}

// A frozen transducer is a sensor fault, not a repeating acquisition. On a rig that seal
// friction holds at rest, p2 is quiet enough to repeat its reading one sample in three or more:
// while p1 was frozen, every such sample repeated on both channels, and a frozen p1 was also
// reported as driver_fault. The sample with a faulty channel no longer counts as a repeat.
TEST(RepeatedSamplesReplay, AFrozenChannelIsASensorFaultNotARepeatingAcquisition) {
  sim::Scenario scenario = sim::preset("healthy", 61);
  scenario.duration_s = 200.0;
  const sim::EffectParameter friction[] = {{"F_C", 120.0}};
  scenario.effects.enable("coulomb_friction", friction);
  capture::Capture pressures = test::columns_of(sim::simulate(scenario), {"t", "p1", "p2"});
  auto& p1 = pressures.column("p1");
  for (std::size_t i = 150 * 500; i < 158 * 500; ++i) p1[i] = p1[150 * 500 - 1];

  const ReplayResult result = replay_capture(pressures, default_replay_config(pressures));
  bool frozen = false;
  for (const auto& e : result.events) {
    EXPECT_NE(e.kind, io::EventKind::driver_fault) << "t " << e.t << ": " << e.message;
    frozen |= e.kind == io::EventKind::alarm_raised && e.alarm == "sensor_fault" &&
              e.channel == "p1" && e.fault == "frozen";
  }
  EXPECT_TRUE(frozen);
}

}  // namespace
}  // namespace leakmon::pipeline
