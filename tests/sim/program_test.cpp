// Test programs (MODEL.md "Test programs") and leaks that grow over time: every phase's reference
// checked against MODEL.md's formulas and by properties that do not reuse them (zero crossings of
// a sweep, the triangle's constant speed and corners), phase timing with the last phase to the
// end, the steps phases drawing the paper's levels, the closed loop tracking the program, program
// files with their errors at file:line:column, the capture's phase metadata, and a seal that
// wears (C_L ramping over minutes to hours) in q_int.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "sim/program.hpp"
#include "sim/rig.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/sim/sim_test_support.hpp"

namespace leakmon::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string error_of(const std::string& yaml) {
  try {
    parse_scenario(yaml, "program.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "no error";
}

// hold 10 s, sine 10 s, sweep 20 s, triangle to the end of a 60 s run.
Scenario four_phases() {
  Scenario s;
  s.name = "four-phases";
  s.duration_s = 60.0;
  s.seed = 5;
  s.program = {{.kind = PhaseKind::hold, .X = 0.021, .duration_s = 10.0},
               {.kind = PhaseKind::sine, .F = 0.7, .A = 0.018, .duration_s = 10.0},
               {.kind = PhaseKind::sweep, .F0 = 0.3, .F1 = 2.5, .A = 0.012, .duration_s = 20.0},
               {.kind = PhaseKind::triangle, .P = 3.0, .A = 0.03}};
  return s;
}

TEST(ProgramReference, EveryPhaseFollowsModelFormulaAndTheLastRunsToTheEnd) {
  const Scenario s = four_phases();
  const auto run = testing::run(s);
  ASSERT_EQ(run.size(), 30000u);
  int hold = 0, sine = 0, sweep = 0, triangle = 0;
  for (const RigSample& r : run) {
    const double t = r.t;
    if (t < 10.0) {
      EXPECT_EQ(r.xref, 0.021) << t;
      ++hold;
    } else if (t < 20.0) {
      EXPECT_NEAR(r.xref, 0.018 * std::sin(kTwoPi * 0.7 * (t - 10.0)), 1e-12) << t;
      ++sine;
    } else if (t < 40.0) {
      const double tp = t - 20.0;
      EXPECT_NEAR(r.xref, 0.012 * std::sin(kTwoPi * (0.3 * tp + 2.2 * tp * tp / 40.0)), 1e-12) << t;
      ++sweep;
    } else {
      ++triangle;
    }
  }
  // Phase boundaries on the sample grid: 5000 samples each for hold and sine, 10000 for the
  // sweep, and the triangle takes every sample to the end of the run.
  EXPECT_EQ(hold, 5000);
  EXPECT_EQ(sine, 5000);
  EXPECT_EQ(sweep, 10000);
  EXPECT_EQ(triangle, 10000);
  EXPECT_DOUBLE_EQ(run.back().t, 59.998);
}

TEST(ProgramReference, SweepCrossesZeroAsOftenAsItsFrequencyIntegrates) {
  // A sweep from F0 to F1 over T has (F0 + F1) T zero crossings (twice the integral of its
  // frequency); the last phase's T defaults to the rest of the run.
  const std::vector<Phase> program = {
      {.kind = PhaseKind::steps, .duration_s = 5.0},
      {.kind = PhaseKind::sweep, .F0 = 0.25, .F1 = 3.75, .A = 0.01}};
  ProgramReference reference(program, ReferenceSettings{}, 3, 65.0);
  int crossings = 0;
  double previous = NAN;
  double late_gap = 0.0, last_crossing = NAN;
  for (int k = 0; k < 650000; ++k) {
    const double t = k * 1e-4;  // finer than the sample grid: crossings near 3.75 Hz are exact
    const double r = reference.at(t);
    if (t < 5.0) continue;
    if (!std::isnan(previous) && t > 5.0 && ((previous < 0.0) != (r < 0.0))) {
      ++crossings;
      if (!std::isnan(last_crossing) && t > 64.0) late_gap = t - last_crossing;
      last_crossing = t;
    }
    previous = r;
  }
  EXPECT_NEAR(crossings, (0.25 + 3.75) * 60.0, 2.0);
  // Near the end the instantaneous frequency is F1: half a period between crossings.
  EXPECT_NEAR(late_gap, 0.5 / 3.75, 0.01);
}

TEST(ProgramReference, TriangleRampsAtConstantSpeedBetweenPlusAndMinusA) {
  const std::vector<Phase> program = {{.kind = PhaseKind::triangle, .P = 2.0, .A = 0.04}};
  ProgramReference reference(program, ReferenceSettings{}, 1, 10.0);
  const double dt = 0.002, speed = 4.0 * 0.04 / 2.0;
  double previous = reference.at(0.0);
  EXPECT_EQ(previous, 0.0);  // rising from 0 at t' = 0
  double highest = previous, lowest = previous;
  int rising = 0, falling = 0;
  for (int k = 1; k < 5000; ++k) {
    const double t = k * dt;
    const double r = reference.at(t);
    highest = std::max(highest, r);
    lowest = std::min(lowest, r);
    // Away from the corners (every P/2, offset P/4) the slope is +-4A/P.
    const double since_corner = std::fmod(t + 0.5, 1.0);
    if (since_corner > 1.5 * dt && since_corner < 1.0 - 0.5 * dt) {
      const double slope = (r - previous) / dt;
      EXPECT_NEAR(std::abs(slope), speed, 1e-9) << t;
      (slope > 0 ? rising : falling) += 1;
    }
    previous = r;
  }
  EXPECT_NEAR(highest, 0.04, 1e-12);
  EXPECT_NEAR(lowest, -0.04, 1e-12);
  EXPECT_NEAR(rising, falling, 10);
  // The first quarter period rises: A/2 at t' = P/8, +A at P/4, 0 at P/2, -A at 3P/4, 0 at P.
  ProgramReference again(program, ReferenceSettings{}, 1, 10.0);
  EXPECT_NEAR(again.at(0.25), 0.02, 1e-12);
  EXPECT_NEAR(again.at(0.5), 0.04, 1e-12);
  EXPECT_NEAR(again.at(1.0), 0.0, 1e-12);
  EXPECT_NEAR(again.at(1.5), -0.04, 1e-12);
  EXPECT_NEAR(again.at(2.0), 0.0, 1e-12);
}

TEST(ProgramReference, StepsPhasesDrawThePapersLevels) {
  // One steps phase is the run without a program, bit for bit.
  Scenario plain = four_phases();
  plain.program.clear();
  Scenario one = plain;
  one.program = {{.kind = PhaseKind::steps}};
  const auto a = testing::run(plain), b = testing::run(one);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].xref, b[k].xref) << k;
    ASSERT_EQ(a[k].p1, b[k].p1) << k;
    ASSERT_EQ(a[k].u, b[k].u) << k;
  }
  // steps 12 s, hold, steps to the end: the first phase is the plain run's start; the second
  // steps phase starts a new level of the paper's range at its own start.
  Scenario split = plain;
  split.program = {{.kind = PhaseKind::steps, .duration_s = 12.0},
                   {.kind = PhaseKind::hold, .X = 0.0, .duration_s = 8.0},
                   {.kind = PhaseKind::steps}};
  const auto c = testing::run(split);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const double t = c[k].t;
    if (t < 12.0) {
      ASSERT_EQ(c[k].xref, a[k].xref) << t;
    } else if (t < 20.0) {
      ASSERT_EQ(c[k].xref, 0.0) << t;
    } else {
      EXPECT_GE(std::abs(c[k].xref), 0.025) << t;
      EXPECT_LE(std::abs(c[k].xref), 0.05) << t;
    }
  }
  // Levels hold 0.5-4 s from the phase's start: within the first 0.5 s of the second steps
  // phase no level changes.
  for (std::size_t k = 10000; k < 10250; ++k) ASSERT_EQ(c[k].xref, c[10000].xref) << c[k].t;
}

TEST(ProgramReference, ClosedLoopTracksTheProgram) {
  Scenario s = four_phases();
  s.params.sigma_w = 0.0;
  s.sensors.enabled = false;
  const auto run = testing::run(s);
  // The end of the hold: at X (the spring's load held by the loop).
  EXPECT_NEAR(testing::mean_over(run, 8.0, 10.0, [](const RigSample& r) { return r.x_true; }),
              0.021, 5e-4);
  // The sine: the piston's amplitude through prefilter and loop within 15 % of A at 0.7 Hz.
  double high = -1.0, low = 1.0;
  for (const RigSample& r : run) {
    if (r.t < 15.0 || r.t >= 20.0) continue;
    high = std::max(high, r.x_true);
    low = std::min(low, r.x_true);
  }
  EXPECT_NEAR(0.5 * (high - low), 0.018, 0.15 * 0.018);
}

TEST(ProgramSpans, PhasesSitInTheRunAndTheLastEndsWithIt) {
  const std::vector<Phase> program = {
      {.kind = PhaseKind::hold, .X = 0.01, .duration_s = 180.0},
      {.kind = PhaseKind::steps, .duration_s = 300.0},
      {.kind = PhaseKind::sine, .F = 1, .A = 0.01, .duration_s = 420.0}};
  auto spans = phase_spans(program, 600.0);
  ASSERT_EQ(spans.size(), 3u);
  EXPECT_EQ(spans[0].start, 0.0);
  EXPECT_EQ(spans[0].end, 180.0);
  EXPECT_EQ(spans[1].start, 180.0);
  EXPECT_EQ(spans[1].end, 480.0);
  EXPECT_EQ(spans[2].start, 480.0);
  EXPECT_EQ(spans[2].end, 600.0);  // the last phase ends with the run, whatever its length
  spans = phase_spans(program, 2000.0);
  EXPECT_EQ(spans[2].end, 2000.0);
  spans = phase_spans(program, 400.0);  // the run ends in the second phase
  EXPECT_EQ(spans[1].end, 400.0);
  EXPECT_EQ(spans[2].start, 400.0);
  EXPECT_EQ(spans[2].end, 400.0);
}

TEST(ProgramFiles, ReadPhasesAndWriteThemIntoTheMetadata) {
  const Scenario s = parse_scenario(R"(name: shift
duration_s: 1000
program:
  - {phase: hold, X: -0.03, duration_s: 180}
  - {phase: steps, duration_s: 300}
  - {phase: sine, F: 0.5, A: 0.02, duration_s: 240}
  - {phase: sweep, F0: 0.2, F1: 2, A: 0.015, duration_s: 120}
  - {phase: triangle, P: 4, A: 0.03}
)",
                                    "shift.yaml");
  ASSERT_EQ(s.program.size(), 5u);
  EXPECT_EQ(s.program[0].kind, PhaseKind::hold);
  EXPECT_EQ(s.program[0].X, -0.03);
  EXPECT_EQ(s.program[2].F, 0.5);
  EXPECT_EQ(s.program[3].F1, 2.0);
  EXPECT_EQ(s.program[4].P, 4.0);
  EXPECT_EQ(s.program[4].duration_s, 0.0);
  const capture::Metadata meta = capture_metadata(s);
  std::vector<std::string> phases;
  std::string program;
  for (const auto& [key, value] : meta) {
    if (key == "phase") phases.push_back(value);
    if (key == "program") program = value;
  }
  EXPECT_EQ(program,
            "hold -0.03 for 180 s; steps for 300 s; sine 0.5 0.02 for 240 s; sweep 0.2 2 0.015 "
            "for 120 s; triangle 4 0.03 to the end");
  ASSERT_EQ(phases.size(), 5u);
  EXPECT_EQ(phases[0], "hold -0.03 start_s=0 end_s=180");
  EXPECT_EQ(phases[3], "sweep 0.2 2 0.015 start_s=720 end_s=840");
  EXPECT_EQ(phases[4], "triangle 4 0.03 start_s=840 end_s=1000");
  // Without a program no program metadata (a steps run's capture reads as before).
  Scenario plain = s;
  plain.program.clear();
  for (const auto& [key, value] : capture_metadata(plain)) {
    EXPECT_NE(key, "program");
    EXPECT_NE(key, "phase");
  }
}

TEST(ProgramFiles, ErrorsNameFileLineColumnAndField) {
  // Unknown phase kind.
  std::string e = error_of("program:\n  - {phase: steps, duration_s: 10}\n  - {phase: chirp}\n");
  EXPECT_NE(e.find("program.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("program[1].phase"), std::string::npos) << e;
  EXPECT_NE(e.find("chirp"), std::string::npos) << e;
  EXPECT_NE(e.find("triangle"), std::string::npos) << e;
  // A phase before the last without a length.
  e = error_of("program:\n  - {phase: sine, F: 1, A: 0.01}\n  - {phase: steps}\n");
  EXPECT_NE(e.find("program.yaml:2:5"), std::string::npos) << e;
  EXPECT_NE(e.find("program[0]"), std::string::npos) << e;
  EXPECT_NE(e.find("duration_s"), std::string::npos) << e;
  // A sine without its amplitude.
  e = error_of("program:\n  - {phase: sine, F: 1}\n");
  EXPECT_NE(e.find("program.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("'A'"), std::string::npos) << e;
  // A key another kind has.
  e = error_of("program:\n  - phase: hold\n    X: 0.01\n    F: 2\n");
  EXPECT_NE(e.find("program.yaml:4:5"), std::string::npos) << e;
  EXPECT_NE(e.find("program[0].F"), std::string::npos) << e;
  // A hold outside the stroke (L/2 = 0.305 m), and one of another rig's shorter stroke.
  e = error_of("program:\n  - {phase: hold, X: 0.4}\n");
  EXPECT_NE(e.find("program.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("program[0].X"), std::string::npos) << e;
  EXPECT_NE(e.find("stroke"), std::string::npos) << e;
  e = error_of("params: {L: 0.1}\nprogram:\n  - {phase: triangle, P: 2, A: 0.06}\n");
  EXPECT_NE(e.find("program.yaml:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("program[0].A"), std::string::npos) << e;
  // Out of range, wrong type, not a list, no phase.
  e = error_of("program:\n  - {phase: triangle, P: 0, A: 0.01}\n");
  EXPECT_NE(e.find("program[0].P"), std::string::npos) << e;
  e = error_of("program:\n  - {phase: sweep, F0: slow, F1: 2, A: 0.01}\n");
  EXPECT_NE(e.find("program.yaml:2:"), std::string::npos) << e;
  EXPECT_NE(e.find("program[0].F0"), std::string::npos) << e;
  e = error_of("program: {phase: steps}\n");
  EXPECT_NE(e.find("program.yaml:1:"), std::string::npos) << e;
  EXPECT_NE(e.find("list of phases"), std::string::npos) << e;
  e = error_of("program:\n  - {X: 0.01, duration_s: 5}\n");
  EXPECT_NE(e.find("program.yaml:2:5"), std::string::npos) << e;
  EXPECT_NE(e.find("phase is required"), std::string::npos) << e;
  e = error_of("program:\n  - {phase: steps, duration_s: 0}\n");
  EXPECT_NE(e.find("program[0].duration_s"), std::string::npos) << e;
}

TEST(LeakGrowth, WearRampsQIntLinearlyOverHours) {
  // A seal that wears from 0 at 30 s to 3e-12 over four hours (beyond the old 1e4 s bound of
  // ramp_s). Simulate the first two minutes and compare q_int with C_L(t) (p1 - p2).
  Scenario s = parse_scenario(R"(name: wear
duration_s: 120
seed: 9
effects:
  internal_leakage: {C_L: 3.0e-12, onset_s: 30, ramp_s: 14400}
)",
                              "wear.yaml");
  ASSERT_TRUE(s.effects.internal_leakage);
  EXPECT_EQ(s.effects.internal_leakage->ramp_s, 14400.0);
  const auto run = testing::run(s);
  int checked = 0;
  for (const RigSample& r : run) {
    const double load = std::max(r.p1_true, 0.0) - std::max(r.p2_true, 0.0);
    if (r.t < 30.0) {
      ASSERT_EQ(r.q_int, 0.0) << r.t;
      continue;
    }
    if (std::abs(load) < 1e5) continue;
    const double expected = 3.0e-12 * (r.t - 30.0) / 14400.0;
    EXPECT_NEAR(r.q_int / load, expected, 1e-9 * 3.0e-12) << r.t;
    ++checked;
  }
  EXPECT_GT(checked, 40000);
  // At the end of the ramp and after it: the full size, held.
  LeakSchedule schedule{3.0e-12, 30.0, 14400.0};
  EXPECT_DOUBLE_EQ(schedule.at(30.0 + 7200.0), 1.5e-12);
  EXPECT_DOUBLE_EQ(schedule.at(30.0 + 14400.0), 3.0e-12);
  EXPECT_DOUBLE_EQ(schedule.at(1e6), 3.0e-12);
  // The limit: a million seconds.
  const std::string e = error_of("effects:\n  internal_leakage: {C_L: 1.0e-12, ramp_s: 2.0e6}\n");
  EXPECT_NE(e.find("effects.internal_leakage.ramp_s"), std::string::npos) << e;
}

}  // namespace
}  // namespace leakmon::sim
