// The flow balance in motion (flow_law) on the simulated rig of MODEL.md: per-sample u, x, p1,
// p2 in hops as the daemon forms them (Observation::u_samples ...), fed straight to the detector.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

#include "config/yaml_reader.hpp"
#include "detect/factory.hpp"
#include "detect/flow_law_detector.hpp"
#include "sim/rig_description.hpp"
#include "sim/simulate.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/hop_observation.hpp"

namespace leakmon::detect {
namespace {

constexpr std::size_t kStep = 20;  // samples per hop at 500 Hz
constexpr double kHop = 0.04;

struct Outcome {
  double first_raise = -1.0;
  double max_score = 0.0;  // before `onset`
  double learned_at = -1.0;
  bool waited = false;  // reported waiting for excitation at some hop
  Decision at_raise;    // the decision of the first raise after `onset`
  Decision last;
};

sim::Phase phase(sim::PhaseKind kind, double duration) {
  sim::Phase p;
  p.kind = kind;
  p.duration_s = duration;
  return p;
}

sim::Phase sine(double seconds, double frequency, double amplitude) {
  sim::Phase p = phase(sim::PhaseKind::sine, seconds);
  p.F = frequency;
  p.A = amplitude;
  return p;
}

sim::Scenario program(std::uint64_t seed, const std::vector<sim::Phase>& phases, double seconds) {
  sim::Scenario s;
  s.controller = sim::ControllerKind::fault_tolerant;
  s.seed = seed;
  s.duration_s = seconds;
  s.program = phases;
  return s;
}

// Feeds the capture hop by hop; `detector` starts fresh (or as restored).
Outcome run(FlowLawDetector& detector, const capture::Capture& capture, double onset,
            std::size_t first_row = 0, std::size_t end_row = 0,
            std::uint64_t* allocations = nullptr) {
  if (end_row == 0) end_row = capture.rows();
  Outcome outcome;
  for (std::size_t start = first_row; start + kStep <= end_row; start += kStep) {
    const Observation o = test::hop_observation(capture, start, kStep);
    {
      test::AllocationScope scope;
      outcome.last = detector.update(o);
      if (allocations != nullptr) *allocations += scope.count();
    }
    outcome.waited = outcome.waited || detector.waiting_for_excitation();
    if (outcome.learned_at < 0.0 && !outcome.last.learning) outcome.learned_at = o.t;
    if (std::isnan(outcome.last.score)) continue;
    if (o.t < onset) outcome.max_score = std::max(outcome.max_score, outcome.last.score);
    if (o.t >= onset && outcome.first_raise < 0.0 &&
        outcome.last.score >= detector.raise_threshold()) {
      outcome.first_raise = o.t;
      outcome.at_raise = outcome.last;
    }
  }
  return outcome;
}

FlowLawDetector make(const FlowLawOptions& options = FlowLawOptions{}) {
  return FlowLawDetector(options, kHop);
}

// The keys layout 5 added (the valve's null-offset regressor): the builds before wrote none.
bool added_in_layout_five(const std::string& key) {
  return key == "learned.null_offset" || key == "coefficient.null_offset" ||
         key == "null_offset.fit" || key == "sample.null_offset_gain" || key == "block.null_offset";
}

// The keys layout 8 added (the tank-offset regressor).
bool added_in_layout_eight(const std::string& key) {
  return key == "learned.tank_offset" || key == "coefficient.tank_offset" ||
         key == "tank_offset.fit" || key == "sample.tank_offset_gain" || key == "block.tank_offset";
}

// A state of this build, written without the tank offset (learn_tank_pressure false), as a build
// of `layout` (6 or 7) wrote it: the keys added since and those `skip` names left out, the learned
// range without the tank offset's axis.
template <typename Skip>
DetectorState as_layout(const DetectorState& current, int layout, Skip skip) {
  DetectorState old("flow_law", layout);
  constexpr std::size_t kNow = FlowLawDetector::kRegressors, kThen = kNow - 1;
  for (const auto& [key, values] : current.entries()) {
    if (added_in_layout_eight(key) || skip(key)) continue;
    if (key == "range.inverse_normal") {
      std::vector<double> without_tank(kThen * kThen);
      for (std::size_t column = 0; column < kThen; ++column) {
        for (std::size_t row = 0; row < kThen; ++row) {
          without_tank[column * kThen + row] = values[column * kNow + row];
        }
      }
      old.put(key, without_tank);
      continue;
    }
    old.put(key, values);
  }
  return old;
}

// Steps, then a sine in which a 1e-12 leak opens: raised within 10 s, sized within 20 %; the same
// run without the leak raises nothing.
TEST(FlowLaw, LeakOpeningInASineIsFoundAndSized) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 130.0),
                                    phase(sim::PhaseKind::sine, 0.0)};
  phases[1].F = 1.5;
  phases[1].A = 0.02;
  sim::Scenario healthy = program(5, phases, 220.0);
  sim::Scenario leaking = healthy;
  constexpr double kOnset = 170.0;
  leaking.effects.internal_leakage = sim::InternalLeakage{1e-12, kOnset, 0.0};

  FlowLawDetector clean = make();
  const Outcome h = run(clean, sim::simulate(healthy), 1e9);
  EXPECT_GT(h.learned_at, 0.0);
  EXPECT_LT(h.max_score, clean.raise_threshold());
  ASSERT_FALSE(std::isnan(h.last.leak_coefficient));
  EXPECT_LT(std::abs(h.last.leak_coefficient), 2e-13);

  FlowLawDetector detector = make();
  const Outcome l = run(detector, sim::simulate(leaking), kOnset);
  EXPECT_LT(l.max_score, detector.raise_threshold());
  ASSERT_GT(l.first_raise, 0.0);
  EXPECT_LT(l.first_raise - kOnset, 10.0);
  EXPECT_NEAR(l.last.leak_coefficient, 1e-12, 0.2e-12);
  EXPECT_GT(l.last.leak_coefficient_ci, 0.0);
}

// The size an alarm states when it raises: the CUSUM leaves zero on healthy blocks' noise too, so
// its run holds blocks from before the onset; sized from all of them the leak came out low with
// an interval too narrow to cover it (11 % low, +-4 %, on a told rig through the pipeline). Sized
// from the change point within the run, the interval covers the truth in (nearly) every run and
// the error is centred. Steps (the paper's test program), 1e-12 and 2e-12 leaks, 12 draws.
TEST(FlowLaw, TheSizeAtTheRaiseIsFromTheChangePointAndItsIntervalCoversTheTruth) {
  constexpr int kRuns = 12;
  int raised = 0, covered = 0;
  std::vector<double> errors;
  for (int i = 0; i < kRuns; ++i) {
    const double leak = i % 2 == 0 ? 1e-12 : 2e-12;
    const double onset = 110.0 + 3.7 * i;
    sim::Scenario s = program(300 + static_cast<std::uint64_t>(i),
                              {phase(sim::PhaseKind::steps, 0.0)}, onset + 30.0);
    s.effects.internal_leakage = sim::InternalLeakage{leak, onset, 0.0};
    FlowLawDetector detector = make();
    const Outcome o = run(detector, sim::simulate(s), onset);
    EXPECT_LT(o.max_score, detector.raise_threshold()) << i;
    if (o.first_raise < 0.0) continue;
    ++raised;
    const double error = o.at_raise.leak_coefficient / leak - 1.0;
    const double half_width = o.at_raise.leak_coefficient_ci / leak;
    std::printf("run %d: %.0e raised %.1f s after the onset, sized %+.1f %% +- %.1f %%\n", i, leak,
                o.first_raise - onset, 100.0 * error, 100.0 * half_width);
    errors.push_back(error);
    covered += std::abs(error) <= half_width ? 1 : 0;
  }
  EXPECT_EQ(raised, kRuns);
  EXPECT_GE(covered, kRuns - 1);  // 95 %: one miss in 12 is within chance (p = 0.12)
  std::sort(errors.begin(), errors.end());
  ASSERT_FALSE(errors.empty());
  EXPECT_LT(std::abs(errors[errors.size() / 2]), 0.05);  // the median error: not biased low
}

// A position transducer pinned at its rail (MODEL.md sensor faults: saturated) is held by the
// daemon only once the plausibility check has seen it, and a hop or two of the rail reach the
// detector first: one block of thousands of spreads. With the leak's sign opposite it does not
// move the CUSUM, but it went into the drift reference, and when the window reached it 30 s
// later the reference moved by tens of spreads: internal_leakage on a healthy rig (an evaluation
// run, x saturated low for 26 s). Both rails, the detector held for 20 s after two such hops.
TEST(FlowLaw, APositionPinnedAtItsRailBeforeTheHoldDoesNotRaise) {
  sim::Scenario s = program(41, {phase(sim::PhaseKind::steps, 0.0)}, 190.0);
  const capture::Capture capture = sim::simulate(s);
  constexpr double kFault = 120.12, kHeld = 20.0;  // two hops before a block ends
  for (const double rail : {-0.305, 0.305}) {
    SCOPED_TRACE(rail);
    capture::Capture faulty = capture;
    auto& x = faulty.column("x");
    const auto& t = faulty.column("t");
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (t[i] >= kFault && t[i] < kFault + kHeld) x[i] = rail;
    }
    FlowLawDetector detector = make();
    const auto fault_row = static_cast<std::size_t>(std::lround(kFault * 500.0));
    // Up to the block's end that the two rail hops close, then held, then on.
    const std::size_t block_rows = 5 * kStep;
    const std::size_t seen_until = (fault_row / block_rows + 1) * block_rows;
    ASSERT_GE(seen_until - fault_row, kStep);
    const Outcome before = run(detector, faulty, 1e9, 0, seen_until);
    EXPECT_FALSE(before.last.learning);
    const std::size_t resume = static_cast<std::size_t>((kFault + kHeld + 2.0) * 500.0);
    const Outcome after = run(detector, faulty, 1e9, resume);
    EXPECT_LT(before.max_score, detector.raise_threshold());
    EXPECT_LT(after.max_score, detector.raise_threshold());
  }
}

// Learned on steps with a rig that differs from its table (beta -25 %, Kv +9 %, m, b), then
// judged on a triangle and a sweep: nothing raises, the added leak estimate stays near 0.
TEST(FlowLaw, MisStatedRigJudgedOnTriangleAndSweepStaysQuiet) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 130.0),
                                    phase(sim::PhaseKind::triangle, 60.0),
                                    phase(sim::PhaseKind::sweep, 60.0)};
  phases[1].P = 4.0;
  phases[1].A = 0.03;
  phases[2].F0 = 0.2;
  phases[2].F1 = 3.0;
  phases[2].A = 0.02;
  sim::Scenario s = program(9, phases, 250.0);
  s.params.beta *= 0.75;
  s.params.Kv *= 1.09;
  s.params.m = 15.0;
  s.params.b = 400.0;
  FlowLawDetector detector = make();
  const Outcome o = run(detector, sim::simulate(s), 1e9);
  EXPECT_GT(o.learned_at, 0.0);
  EXPECT_LT(o.max_score, detector.raise_threshold());
  // a = Kv_table / Kv_true absorbs the valve's error.
  EXPECT_NEAR(detector.coefficients()[0], 1.0 / 1.09, 0.03);
  ASSERT_FALSE(std::isnan(o.last.leak_coefficient));
  EXPECT_LT(std::abs(o.last.leak_coefficient), 2e-13);
}

// A hold alone gives one load: the learning period passes, the detector waits for excitation,
// and learns once steps begin.
TEST(FlowLaw, HoldOnlyStartWaitsForExcitation) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::hold, 60.0),
                                    phase(sim::PhaseKind::steps, 0.0)};
  phases[0].X = 0.01;
  const capture::Capture capture = sim::simulate(program(3, phases, 120.0));
  FlowLawOptions options;
  options.learning.learn_seconds = 30.0;
  FlowLawDetector detector = make(options);
  const std::size_t hold_end = static_cast<std::size_t>(60.0 * 500.0);
  const Outcome hold = run(detector, capture, 1e9, 0, hold_end);
  EXPECT_LT(hold.learned_at, 0.0);
  EXPECT_TRUE(hold.waited);
  EXPECT_TRUE(detector.waiting_for_excitation());
  EXPECT_TRUE(hold.last.learning);
  EXPECT_TRUE(std::isnan(hold.last.learning_hops_left));
  EXPECT_FALSE(hold.last.judged);
  EXPECT_EQ(hold.last.not_judged_reason, NotJudgedReason::waiting_for_excitation);
  const Outcome steps = run(detector, capture, 1e9, hold_end);
  EXPECT_GT(steps.learned_at, 60.0);
  EXPECT_FALSE(detector.waiting_for_excitation());
  EXPECT_FALSE(steps.last.learning);
  EXPECT_TRUE(steps.last.judged);
  EXPECT_EQ(steps.last.not_judged_reason, NotJudgedReason::none);
}

// Issue 23: a program that starts with a hold and runs a slow sine before its steps. By the
// spread of its loads alone (min_rest_loads 0, the build before the wait for rest loads or
// identifying motion) the detector learned 22 s into the sine, on a window mostly the hold, and
// the steps raised internal_leakage on a healthy rig. Then it waited through the hold and the
// sine (a window three quarters hold) and learned on the steps. Now the sine's motion starts
// the learning period over and it is learned on the sine alone, 90 s into it; the steps after
// it lie almost all within what the sine taught (29 and 39 of their 600 blocks outside), are
// judged, and raise nothing. Two draws.
TEST(FlowLaw, AHoldThenASineIsLearnedOnTheSineAndTheStepsAfterRaiseNothing) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::hold, 100.0),
                                    phase(sim::PhaseKind::sine, 100.0),
                                    phase(sim::PhaseKind::steps, 0.0)};
  phases[0].X = 0.02;
  phases[1].F = 0.2;
  phases[1].A = 0.03;
  constexpr double kSineStart = 100.0, kStepsStart = 200.0;
  const double learn_seconds = FlowLawOptions{}.learning.learn_seconds;
  const std::size_t steps_row = static_cast<std::size_t>(kStepsStart * 500.0);
  for (const std::uint64_t seed : {2531u, 7u}) {
    const capture::Capture capture = sim::simulate(program(seed, phases, 320.0));
    FlowLawDetector detector = make();
    const Outcome before = run(detector, capture, 1e9, 0, steps_row);
    EXPECT_TRUE(before.waited) << seed;  // through the hold
    EXPECT_EQ(detector.learning_restarts(), 1u) << seed;
    EXPECT_GT(before.learned_at, kSineStart + learn_seconds - 1.0) << seed;
    EXPECT_LT(before.learned_at, kStepsStart) << seed;
    EXPECT_LT(before.max_score, detector.raise_threshold()) << seed;
    const Outcome steps = run(detector, capture, 1e9, steps_row);
    std::printf("seed %llu: learned at %.1f, steps' max score %.3f, blocks outside %zu\n",
                static_cast<unsigned long long>(seed), before.learned_at, steps.max_score,
                detector.blocks_not_judged_outside_learned_range());
    EXPECT_LT(steps.max_score, detector.raise_threshold()) << seed;
    EXPECT_LT(detector.blocks_not_judged_outside_learned_range(), 120u) << seed;
    EXPECT_TRUE(steps.last.judged) << seed;
  }
}

// Motion identifies the load term when the volumes leave most of its spread unexplained: a
// triangle (share 0.99) is learned at the end of its learning period. A fast sine's load term is
// nearly a mix of the volumes (share 0.26-0.54; at 2.5 Hz a 0.2 s block is half a period and
// the share is 0): asked to (`min_motion_load_share` 0.9) learning waits through it and through
// a sweep after it (0.6-0.86 in 30-90 s windows) until the triangle ends the wait. By default
// moving blocks are enough: the sine is learned where it runs and judged there (a leak in it
// raises), and what the sine cannot tell about the load term is what the learned range keeps
// from being judged elsewhere: the sweep and the triangle after it are not judged by the sine's
// model until a range extension shows it describes them (docs/detection.md).
TEST(FlowLaw, ATriangleIsLearnedByItsMotionAFastSineTooAndJudgedInItsOwnRange) {
  FlowLawOptions options;
  options.learning.learn_seconds = 30.0;
  sim::Phase triangle = phase(sim::PhaseKind::triangle, 0.0);
  triangle.P = 4.0;
  triangle.A = 0.03;
  {
    FlowLawDetector detector = make(options);
    const Outcome o = run(detector, sim::simulate(program(41, {triangle}, 80.0)), 1e9);
    EXPECT_GT(o.learned_at, 0.0);
    EXPECT_LT(o.learned_at, 33.0);  // at the end of the learning period
    EXPECT_FALSE(o.waited);
    EXPECT_EQ(detector.excitation().rest_loads, 0u);
    EXPECT_GE(detector.excitation().motion_load_share, 0.9);
    EXPECT_LT(o.max_score, detector.raise_threshold());
  }
  const sim::Phase fast_sine = sine(60.0, 1.5, 0.02);
  sim::Phase sweep = phase(sim::PhaseKind::sweep, 30.0);
  sweep.F0 = 0.2;
  sweep.F1 = 3.0;
  sweep.A = 0.02;
  triangle.duration_s = 0.0;
  const capture::Capture capture = sim::simulate(program(43, {fast_sine, sweep, triangle}, 180.0));
  {
    FlowLawOptions identifying = options;
    identifying.min_motion_load_share = 0.9;
    FlowLawDetector detector = make(identifying);
    const Outcome in_sine = run(detector, capture, 1e9, 0, 60 * 500);
    EXPECT_LT(in_sine.learned_at, 0.0);
    EXPECT_TRUE(detector.waiting_for_excitation());
    EXPECT_EQ(in_sine.last.not_judged_reason, NotJudgedReason::waiting_for_excitation);
    EXPECT_LT(detector.excitation().motion_load_share, 0.9);
    const Outcome later = run(detector, capture, 1e9, 60 * 500);
    EXPECT_GT(later.learned_at, 90.0);  // in the triangle
    EXPECT_FALSE(detector.waiting_for_excitation());
    EXPECT_GE(detector.excitation().motion_load_share, 0.9);
    EXPECT_LT(later.max_score, detector.raise_threshold());
  }
  FlowLawDetector detector = make(options);
  const Outcome in_sine = run(detector, capture, 1e9, 0, 60 * 500);
  EXPECT_GT(in_sine.learned_at, 0.0);
  EXPECT_LT(in_sine.learned_at, 33.0);
  EXPECT_FALSE(in_sine.waited);
  EXPECT_LT(detector.excitation().motion_load_share, 0.9);
  EXPECT_TRUE(in_sine.last.judged);
  const Outcome later = run(detector, capture, 1e9, 60 * 500);
  EXPECT_GT(detector.blocks_not_judged_outside_learned_range(), 0u);
  EXPECT_LT(std::max(in_sine.max_score, later.max_score), detector.raise_threshold());
  std::printf("sine, sweep, triangle: learned at %.1f s, share %.3f, %zu blocks outside\n",
              in_sine.learned_at, detector.excitation().motion_load_share,
              detector.blocks_not_judged_outside_learned_range());

  sim::Scenario leaking = program(43, {fast_sine, sweep, triangle}, 180.0);
  sim::InternalLeakage leak;
  leak.C_L = 1e-12;
  leak.onset_s = 45.0;
  leaking.effects.internal_leakage = leak;
  FlowLawDetector judge = make(options);
  const Outcome found = run(judge, sim::simulate(leaking), leak.onset_s);
  EXPECT_LT(found.max_score, judge.raise_threshold());  // before the onset
  EXPECT_GT(found.first_raise, leak.onset_s);
  EXPECT_LT(found.first_raise, leak.onset_s + 15.0);  // in the sine
  std::printf("leak in the sine from %.0f s: raised at %.2f s\n", leak.onset_s, found.first_raise);
}

// Run 7's program in short: a slow 6 s triangle of 35 mm (learned on), then a 0.46-2.5 Hz sweep
// of 27 mm, fault-tolerant controller.
constexpr double kTriangleSeconds = 150.0, kSweepSeconds = 140.0;
sim::Scenario triangle_then_fast_sweep_program(double seconds) {
  sim::Phase triangle = phase(sim::PhaseKind::triangle, kTriangleSeconds);
  triangle.P = 6.0;
  triangle.A = 0.035;
  sim::Phase sweep = phase(sim::PhaseKind::sweep, 0.0);
  sweep.F0 = 0.46;
  sweep.F1 = 2.5;
  sweep.A = 0.027;
  return program(7, {triangle, sweep}, seconds);
}
capture::Capture triangle_then_fast_sweep() {
  return sim::simulate(triangle_then_fast_sweep_program(kTriangleSeconds + kSweepSeconds));
}

// A model learned on a slow triangle judges a fast sweep (run 7 of `evaluate --conditions
// programs --seed 2531`: a 6 s triangle, then a 0.46-2.5 Hz sweep of 27 mm that raised 273 s in).
// A triangle opens the valve slowly and shows little of the spool's lag; the sweep's lag term is
// tens of times the triangle's, and a lag learned a few tenths of a millisecond off left residuals
// following the load's sign by 5 spreads there. The sweep's blocks beyond twice the largest
// learning leverage are not judged and say so; the triangle after learning, and the sweep's slow
// start, are judged; nothing raises. With the guard off every block is judged.
TEST(FlowLaw, AFastSweepBeyondWhatATriangleTaughtIsNotJudged) {
  const capture::Capture capture = triangle_then_fast_sweep();
  const std::size_t sweep_row = static_cast<std::size_t>(kTriangleSeconds * 500.0);
  FlowLawOptions guarded;
  guarded.range_extension_seconds = 0.0;  // the next test extends the range
  FlowLawDetector detector = make(guarded);
  const Outcome in_triangle = run(detector, capture, 1e9, 0, sweep_row);
  EXPECT_GT(in_triangle.learned_at, 90.0);
  EXPECT_LT(in_triangle.learned_at, 150.0);
  EXPECT_GT(detector.max_learned_leverage(), 0.0);
  EXPECT_EQ(detector.blocks_not_judged_outside_learned_range(), 0u);
  EXPECT_TRUE(in_triangle.last.judged);
  const Outcome in_sweep = run(detector, capture, 1e9, sweep_row);
  const std::size_t outside = detector.blocks_not_judged_outside_learned_range();
  std::printf(
      "triangle, then sweep: learned at %.1f s, largest learning leverage %.3f, %zu of "
      "%.0f sweep blocks outside, max score %.3f\n",
      in_triangle.learned_at, detector.max_learned_leverage(), outside, kSweepSeconds / 0.2,
      std::max(in_triangle.max_score, in_sweep.max_score));
  EXPECT_GT(outside, 100u);                          // the fast part
  EXPECT_LT(outside, (kSweepSeconds - 20.0) / 0.2);  // its slow start is judged
  EXPECT_FALSE(in_sweep.last.judged);                // at 2.5 Hz
  EXPECT_EQ(in_sweep.last.not_judged_reason, NotJudgedReason::outside_learned_regime);
  EXPECT_LT(std::max(in_triangle.max_score, in_sweep.max_score), detector.raise_threshold());

  FlowLawOptions unguarded = guarded;
  unguarded.max_leverage_ratio = 0.0;
  FlowLawDetector every_block = make(unguarded);
  const Outcome all = run(every_block, capture, 1e9);
  EXPECT_EQ(every_block.blocks_not_judged_outside_learned_range(), 0u);
  EXPECT_TRUE(all.last.judged);
}

// The same program, the range extended: gathered for 30 s, the sweep's blocks are fitted with the
// triangle's normal equations, a load term of their own free in each half; healthy it comes out
// at 1e-14 (+- 2e-14) against the floor's 2.5e-13, so the range is extended and the sweep judged
// to its end without a raise. A 1e-12 leak opening 60 s into the sweep, after the extension, is
// judged and raises. One opening 5 s into the sweep is in the new blocks' load term (1e-12): the
// blocks cannot tell it from a model that does not describe the sweep, so nothing is learned
// from them (a leak is never learned as healthy); it is raised by the sweep's blocks that lie
// within the triangle's range (a sixth of them).
TEST(FlowLaw, ASweepBeyondWhatATriangleTaughtIsLearnedWithoutLearningALeak) {
  const auto with_leak_from = [](double onset) {
    sim::Scenario scenario =
        triangle_then_fast_sweep_program(kTriangleSeconds + kSweepSeconds + 60.0);
    if (onset > 0.0) {
      sim::InternalLeakage leak;
      leak.C_L = 1e-12;
      leak.onset_s = onset;
      scenario.effects.internal_leakage = leak;
    }
    return sim::simulate(scenario);
  };
  FlowLawDetector healthy = make();
  std::uint64_t allocations = 0;
  const Outcome quiet = run(healthy, with_leak_from(0.0), 1e9, 0, 0, &allocations);
  EXPECT_EQ(allocations, 0u);  // gathering and refitting included
  const FlowLawDetector::RangeExtension extension = healthy.range_extension();
  EXPECT_GE(extension.extensions, 1u);
  EXPECT_LT(std::abs(extension.added_leak), 1e-13);
  EXPECT_LT(extension.added_leak_error, 1e-13);
  EXPECT_TRUE(quiet.last.judged);
  EXPECT_LT(quiet.max_score, healthy.raise_threshold());
  std::printf("healthy: %zu extensions, added %.3g +- %.3g, %zu blocks outside\n",
              extension.extensions, extension.added_leak, extension.added_leak_error,
              healthy.blocks_not_judged_outside_learned_range());

  constexpr double kLateOnset = kTriangleSeconds + 60.0;
  FlowLawDetector detector = make();
  const Outcome found = run(detector, with_leak_from(kLateOnset), kLateOnset);
  EXPECT_LT(found.max_score, detector.raise_threshold());
  EXPECT_GT(found.first_raise, kLateOnset);
  EXPECT_LT(found.first_raise, kLateOnset + 60.0);
  std::printf("leak from %.0f s: raised at %.2f s\n", kLateOnset, found.first_raise);

  constexpr double kEarlyOnset = kTriangleSeconds + 5.0;
  FlowLawDetector refusing = make();
  const Outcome refused = run(refusing, with_leak_from(kEarlyOnset), kEarlyOnset);
  EXPECT_GT(refused.first_raise, kEarlyOnset);
  EXPECT_LT(refused.first_raise, kEarlyOnset + 60.0);
  EXPECT_EQ(refusing.range_extension().extensions, 0u);
  EXPECT_GE(refusing.range_extension().attempts, 2u);
  EXPECT_NEAR(refusing.range_extension().added_leak, 1e-12, 0.2e-12);
  std::printf("leak from %.0f s: raised at %.2f s, %zu attempts refused, added %.3g\n", kEarlyOnset,
              refused.first_raise, refusing.range_extension().attempts,
              refusing.range_extension().added_leak);

  FlowLawOptions not_extended;
  not_extended.range_extension_seconds = 0.0;
  FlowLawDetector unextended = make(not_extended);
  const Outcome missed = run(unextended, with_leak_from(kLateOnset), kLateOnset);
  EXPECT_LT(missed.first_raise, 0.0);
  EXPECT_EQ(unextended.range_extension().attempts, 0u);
}

// A 0.2 Hz sine, a 1.7 Hz sine, then steps (fault-tolerant controller). In the slow sine the
// spool lag's flow follows the acceleration, -w^2 x, in phase with the spring's load: of the lag
// regressor's spread the other regressors leave, the load explains 96 %, so the lag is not
// learned there (the stated rung is kept; learned, the ladder chose 20 ms for 2.5 ms and the
// steps raised, score 1.12).
// The fast sine and the steps are outside the slow sine's range until an extension shows that
// the model describes them; nothing raises.
TEST(FlowLaw, ASlowSineDoesNotTeachTheLagAndTheFasterProgramsAfterItRaiseNothing) {
  const sim::Phase slow = sine(300.0, 0.2, 0.03);
  const sim::Phase fast = sine(300.0, 1.7, 0.02);
  const sim::Phase steps = phase(sim::PhaseKind::steps, 0.0);
  for (const std::uint64_t seed : {7u, 2531u}) {
    FlowLawDetector detector = make();
    const Outcome o = run(detector, sim::simulate(program(seed, {slow, fast, steps}, 1000.0)), 1e9);
    EXPECT_GT(o.learned_at, 0.0) << seed;
    EXPECT_LT(o.learned_at, 300.0) << seed;  // in the slow sine
    EXPECT_DOUBLE_EQ(detector.spool_time_constant(), sim::Parameters::nominal().tau) << seed;
    EXPECT_GE(detector.range_extension().extensions, 1u) << seed;
    EXPECT_GT(detector.blocks_not_judged_outside_learned_range(), 0u) << seed;
    EXPECT_TRUE(o.last.judged) << seed;
    EXPECT_LT(o.max_score, 0.5 * detector.raise_threshold()) << seed;
  }
}

// Durability blocks of fast sines (2.79 Hz 25 mm, 2.52 Hz 9.5 mm), then steps: learned by their
// motion at the end of the first learning period and judged in them; a 1e-12 leak opening in the
// second sine raises within seconds. The steps are outside the sines' range; healthy, an
// extension brings them in (their own load term -1.4e-13 to -1.9e-13, within the floor).
TEST(FlowLaw, FastSinesAreLearnedAndJudgedAndALeakInThemRaises) {
  const sim::Phase first = sine(470.0, 2.79, 0.025);
  const sim::Phase second = sine(320.0, 2.52, 0.0095);
  const sim::Phase steps = phase(sim::PhaseKind::steps, 0.0);
  for (const std::uint64_t seed : {7u, 2531u}) {
    const sim::Scenario healthy = program(seed, {first, second, steps}, 1100.0);
    FlowLawDetector detector = make();
    const Outcome o = run(detector, sim::simulate(healthy), 1e9);
    EXPECT_GT(o.learned_at, 0.0) << seed;
    EXPECT_LT(o.learned_at, 100.0) << seed;
    EXPECT_GE(detector.range_extension().extensions, 1u) << seed;
    EXPECT_TRUE(o.last.judged) << seed;
    EXPECT_LT(o.max_score, 0.5 * detector.raise_threshold()) << seed;

    sim::Scenario leaking = healthy;
    sim::InternalLeakage leak;
    leak.C_L = 1e-12;
    leak.onset_s = 500.0;
    leaking.effects.internal_leakage = leak;
    FlowLawDetector judge = make();
    const Outcome found = run(judge, sim::simulate(leaking), leak.onset_s);
    EXPECT_LT(found.max_score, judge.raise_threshold()) << seed;
    EXPECT_GT(found.first_raise, leak.onset_s) << seed;
    EXPECT_LT(found.first_raise, leak.onset_s + 10.0) << seed;
  }
}

// The paper's steps learned on the steps: hardly a block lies beyond the learned range.
TEST(FlowLaw, TheStepsJudgedAfterTheStepsStayInTheLearnedRange) {
  const capture::Capture capture =
      sim::simulate(program(11, {phase(sim::PhaseKind::steps, 0.0)}, 400.0));
  FlowLawDetector detector = make();
  const Outcome o = run(detector, capture, 1e9);
  ASSERT_GT(o.learned_at, 0.0);
  const double blocks = (400.0 - o.learned_at) / 0.2;
  EXPECT_LE(static_cast<double>(detector.blocks_not_judged_outside_learned_range()), 0.01 * blocks);
  EXPECT_LT(o.max_score, detector.raise_threshold());
}

constexpr double kMorningSeconds = 900.0, kMorningOnset = 840.0;

// The paper's steps lie at rest at many loads by the end of the learning period: learned at the
// same block, with the same coefficients, as by the spread alone, and deciding the same.
TEST(FlowLaw, ThePapersStepsLearnAsBefore) {
  sim::Scenario s = program(5, {phase(sim::PhaseKind::steps, 0.0)}, 150.0);
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, 120.0, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawDetector detector = make();
  FlowLawOptions spread_alone;
  spread_alone.min_rest_loads = 0.0;
  FlowLawDetector old_rule = make(spread_alone);
  const Outcome a = run(detector, capture, 120.0);
  const Outcome b = run(old_rule, capture, 120.0);
  EXPECT_GE(detector.excitation().rest_loads, 3u);
  EXPECT_FALSE(a.waited);
  EXPECT_EQ(a.learned_at, b.learned_at);
  EXPECT_EQ(detector.coefficients(), old_rule.coefficients());
  EXPECT_GT(a.first_raise, 120.0);
  EXPECT_EQ(a.first_raise, b.first_raise);
  EXPECT_EQ(a.last.score, b.last.score);
  EXPECT_EQ(a.last.leak_coefficient, b.last.leak_coefficient);
}

// A cold morning (15 degC warming to 48 degC, `temp` and `ps` recorded) on a valve with a null
// offset of 0.08 V (MODEL.md `valve_bias`), the paper's steps: learned cold, the offset's
// turbulent flow does not follow the oil's viscosity. Without a regressor of its own the
// viscosity-scaled load term took it up and over-predicted it as the oil warmed (the morning
// start's false alarms, docs/detection.md): that model raises here before the leak. With the
// null-offset regressor nothing is raised in the warm-up, the coefficient is the offset (-b,
// b = u0 / u_max), and a 1e-12 leak opening in the warm oil is found and sized.
TEST(FlowLaw, AColdStartOnABiasedValveRaisesNothingAndStillFindsALeak) {
  sim::Scenario s = program(23, {phase(sim::PhaseKind::steps, 0.0)}, kMorningSeconds);
  sim::TemperatureProfile warm_up;
  warm_up.kind = sim::TemperatureProfile::Kind::warm_up;
  warm_up.T0 = 15.0;
  warm_up.T_work = 48.0;
  warm_up.tau_s = 300.0;
  s.conditions.temperature = warm_up;
  s.record.ps = s.record.temp = true;
  s.effects.valve_bias = sim::ValveBias{0.08};
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, kMorningOnset, 0.0};
  const capture::Capture capture = sim::simulate(s);

  FlowLawOptions before;
  before.learn_null_offset = false;
  before.max_leverage_ratio = 0.0;
  FlowLawDetector old_model = make(before);
  const Outcome o = run(old_model, capture, kMorningOnset);
  EXPECT_GE(o.max_score, old_model.raise_threshold());

  FlowLawDetector detector = make();
  const Outcome n = run(detector, capture, kMorningOnset);
  EXPECT_GT(n.learned_at, 0.0);
  EXPECT_LT(n.learned_at, 120.0);  // cold: the oil below 25 degC
  EXPECT_LT(n.max_score, 0.5);
  EXPECT_NEAR(detector.coefficients()[5], -0.08 / s.params.u_max, 0.2 * 0.08 / s.params.u_max);
  ASSERT_GT(n.first_raise, kMorningOnset);
  EXPECT_LT(n.first_raise, kMorningOnset + 10.0);
  EXPECT_NEAR(n.at_raise.leak_coefficient, 1e-12, 0.2e-12);
}

// After learning, a hold at the spring's rest position leaves no leak flow to judge: the
// decision says so (no_load) once the last judged block is older than judged_memory_seconds,
// and judges again when the load comes back.
TEST(FlowLaw, HoldAtTheSpringsRestIsSaidAsNotJudged) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 130.0),
                                    phase(sim::PhaseKind::hold, 40.0),
                                    phase(sim::PhaseKind::sine, 0.0)};
  phases[1].X = 0.0;
  phases[2].F = 0.5;
  phases[2].A = 0.02;
  const capture::Capture capture = sim::simulate(program(7, phases, 200.0));
  FlowLawDetector detector = make();
  const std::size_t hold_end = static_cast<std::size_t>(170.0 * 500.0);
  const Outcome to_hold = run(detector, capture, 1e9, 0, hold_end);
  EXPECT_FALSE(to_hold.last.learning);
  EXPECT_FALSE(to_hold.last.judged);
  EXPECT_EQ(to_hold.last.not_judged_reason, NotJudgedReason::no_load);
  EXPECT_LT(to_hold.max_score, detector.raise_threshold());
  const Outcome sine = run(detector, capture, 1e9, hold_end);
  EXPECT_TRUE(sine.last.judged);
  EXPECT_EQ(sine.last.not_judged_reason, NotJudgedReason::none);
  EXPECT_LT(sine.max_score, detector.raise_threshold());
}

// judged_memory_seconds is an option (as flow_balance's): configured longer than the hold at the
// spring's rest, the hold's decisions stay judged; the default (10 s) says no_load there.
TEST(FlowLaw, JudgedMemoryIsConfigured) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 130.0),
                                    phase(sim::PhaseKind::hold, 0.0)};
  phases[1].X = 0.0;
  const capture::Capture capture = sim::simulate(program(7, phases, 160.0));
  const auto node = config::ConfigNode::load_string("judged_memory_seconds: 60\n", "f.yaml");
  auto configured = make_detector("flow_law", {true, true, true, true}, kHop, &node);
  auto* long_memory = dynamic_cast<FlowLawDetector*>(configured.get());
  ASSERT_NE(long_memory, nullptr);
  const Outcome remembered = run(*long_memory, capture, 1e9);
  EXPECT_FALSE(remembered.last.learning);
  EXPECT_TRUE(remembered.last.judged);
  FlowLawDetector by_default = make();
  const Outcome forgotten = run(by_default, capture, 1e9);
  EXPECT_FALSE(forgotten.last.judged);
  EXPECT_EQ(forgotten.last.not_judged_reason, NotJudgedReason::no_load);
}

// A leak opening while learning, after a reference that identifies the model: learned on the
// blocks before it and the blocks after it judged, so it raises internal_leakage when learning
// ends, sized within a quarter; nothing is left to report as learned. With
// learn_before_change false (the build before) it is learned as healthy and only reported
// (learned_change) with its onset. The healthy run does neither.
TEST(FlowLaw, ALeakOpeningWhileLearningIsRaisedWhenLearningEnds) {
  const std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 0.0)};
  sim::Scenario healthy = program(11, phases, 110.0);
  sim::Scenario leaking = healthy;
  constexpr double kOnset = 65.0;
  leaking.effects.internal_leakage = sim::InternalLeakage{2e-12, kOnset, 0.0};
  const capture::Capture leaky = sim::simulate(leaking);
  FlowLawDetector clean = make();
  const Outcome h = run(clean, sim::simulate(healthy), 1e9);
  ASSERT_FALSE(h.last.learning);
  EXPECT_FALSE(clean.learned_change().has_value());
  EXPECT_EQ(clean.changes_judged_after_learning(), 0u);
  EXPECT_LT(h.max_score, clean.raise_threshold());

  FlowLawDetector detector = make();
  const Outcome l = run(detector, leaky, kOnset);
  ASSERT_FALSE(l.last.learning);
  EXPECT_EQ(detector.changes_judged_after_learning(), 1u);
  EXPECT_FALSE(detector.learned_change().has_value());
  ASSERT_GT(l.first_raise, 0.0);
  EXPECT_LT(l.first_raise, l.learned_at + 1.0);  // on the blocks judged when learning ends
  EXPECT_NEAR(l.at_raise.leak_coefficient, 2e-12, 0.5e-12);

  FlowLawOptions report_only;
  report_only.learn_before_change = false;
  FlowLawDetector old = make(report_only);
  const Outcome o = run(old, leaky, kOnset);
  EXPECT_LT(o.first_raise, 0.0);
  const auto change = old.learned_change();
  ASSERT_TRUE(change.has_value());
  EXPECT_EQ(change->feature, "flow_residual");
  EXPECT_NEAR(change->change_t, kOnset, 3.0);
  EXPECT_GT(change->size, 1e-12);
  EXPECT_LT(change->size, 4e-12);
}

// A rig that holds still for minutes, then runs a triangle in which a leak opens 35 s in (run
// 32 of `evaluate --conditions programs --seed 3307`: a 316 s hold, a leak 35 s into a 2.2 s
// triangle, not found in the 90 s the run lasted after it). The wait ended only when a quarter
// of the 180 s window had moved away from the hold's load, here 135 s into the triangle (100 s
// after the onset), on a window a third of which was the hold, and the leak was learned as
// healthy. Now the motion starts the learning period over: 90 s into the triangle the learning
// period's leak check (its reference the triangle's first 36 s) finds the leak, the model is
// learned on the blocks before it and it raises then, 55 s after it opened. The healthy run:
// learned once, nothing raised.
TEST(FlowLaw, ALeakOpeningInTheFirstMotionAfterALongHoldIsRaisedWithinAMinute) {
  constexpr double kHoldSeconds = 200.0;
  constexpr double kOnset = kHoldSeconds + 35.0;
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::hold, kHoldSeconds),
                                    phase(sim::PhaseKind::triangle, 0.0)};
  phases[0].X = 0.03;
  phases[1].P = 2.2;
  phases[1].A = 0.02;
  const sim::Scenario healthy = program(32, phases, kHoldSeconds + 150.0);
  sim::Scenario leaking = healthy;
  leaking.effects.internal_leakage = sim::InternalLeakage{1e-12, kOnset, 0.0};

  FlowLawDetector clean = make();
  const Outcome h = run(clean, sim::simulate(healthy), 1e9);
  EXPECT_EQ(clean.learning_restarts(), 1u);
  EXPECT_GT(h.learned_at, kHoldSeconds + FlowLawOptions{}.learning.learn_seconds);
  EXPECT_LT(h.max_score, clean.raise_threshold());
  EXPECT_TRUE(h.last.judged);

  FlowLawDetector detector = make();
  const Outcome l = run(detector, sim::simulate(leaking), kOnset);
  EXPECT_EQ(detector.learning_restarts(), 1u);
  EXPECT_EQ(detector.changes_judged_after_learning(), 1u);
  ASSERT_GT(l.first_raise, 0.0);
  EXPECT_LT(l.first_raise, kOnset + 60.0);
  EXPECT_NEAR(l.at_raise.leak_coefficient, 1e-12, 0.3e-12);
}

// The daemon holds the detector while a channel is faulty (no update at all): the first block
// after the hold must not integrate from x, p1, p2 before it. A healthy steps-then-sine run
// learned, then held for 5-25 s (so that the sine's position and load differ across the hold)
// stays quiet.
TEST(FlowLaw, HopsNotSeenDoNotMakeABlock) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 120.0),
                                    phase(sim::PhaseKind::sine, 0.0)};
  phases[1].F = 0.7;
  phases[1].A = 0.03;
  const capture::Capture capture = sim::simulate(program(13, phases, 200.0));
  const std::size_t hold_from = 150 * 500 + 7 * kStep;
  FlowLawDetector learned = make();
  const Outcome before = run(learned, capture, 1e9, 0, hold_from);
  ASSERT_FALSE(before.last.learning);
  double worst = 0.0;
  for (std::size_t hops = 125; hops <= 625; hops += 23) {
    FlowLawDetector held = learned;
    const Outcome after = run(held, capture, 1e9, hold_from + hops * kStep);
    worst = std::max(worst, after.max_score);
    EXPECT_LT(after.max_score, 0.5) << hops << " hops not seen";
  }
  std::printf("highest score after a hold: %.3f\n", worst);
}

// A detector restored from another's state mid-run (mid-block) decides as that one would.
TEST(FlowLaw, StateRoundTripDecidesTheSame) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::steps, 50.0),
                                    phase(sim::PhaseKind::sine, 0.0)};
  phases[1].F = 1.0;
  phases[1].A = 0.02;
  sim::Scenario s = program(7, phases, 90.0);
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, 70.0, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions options;
  options.learning.learn_seconds = 40.0;
  FlowLawDetector original = make(options);
  const std::size_t split = 60 * 500 + 3 * kStep;  // inside a block
  run(original, capture, 1e9, 0, split);
  const DetectorState saved = original.export_state();
  FlowLawDetector restored = make(options);
  restored.import_state(saved);
  EXPECT_EQ(restored.export_state(), saved);
  const Outcome a = run(original, capture, 1e9, split);
  const Outcome b = run(restored, capture, 1e9, split);
  EXPECT_FALSE(a.last.learning);
  EXPECT_EQ(a.last.score, b.last.score);
  EXPECT_EQ(a.last.leak_coefficient, b.last.leak_coefficient);
  EXPECT_GT(a.last.score, 0.0);
  EXPECT_EQ(original.export_state(), restored.export_state());

  FlowLawOptions other = options;
  other.block_seconds = 0.04;  // one hop per block: the saved block position does not fit
  FlowLawDetector wrong = make(other);
  EXPECT_THROW(wrong.import_state(saved), StateError);
}

// `leakmon evaluate --rigs other --seed 2951` run 17, not told its rig: a light (2.5 kg), stiff
// rig whose valve lags 1.06 ms against the stated 2.5 ms. On its steps the volumes explain 93 %
// of the lag regressor's spread, but the load term none of what they leave: the lag is told
// apart from the load, so it is learned (kept at the stated rung, as when its whole share was
// weighed, the 9.8e-13 leak was found 22 s late and cleared at once; learned, within 2 s).
TEST(FlowLaw, ALagTheVolumesExplainButTheLoadDoesNotIsLearned) {
  constexpr double kOnset = 142.0;
  sim::Scenario s = program(295108870, {phase(sim::PhaseKind::steps, 0.0)}, 232.0);
  s.params.D = 0.0543063;
  s.params.d = 0.0235361;
  s.params.L = 0.458499;
  s.params.V_dead = 1.46439e-05;
  s.params.V_line = 2.10465e-05;
  s.params.ps = 2.3289e+07;
  s.params.pt = 656130.0;
  s.params.beta = 1.31365e+09;
  s.params.m = 2.499;
  s.params.b = 945.226;
  s.params.K_s = 141494.0;
  s.params.Kv = 3.31031e-07;
  s.params.tau = 0.001059;
  s.effects.internal_leakage = sim::InternalLeakage{9.76494e-13, kOnset, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawDetector detector = make();  // not told: the paper's rig
  const Outcome o = run(detector, capture, kOnset);
  EXPECT_GT(o.learned_at, 0.0);
  EXPECT_NE(detector.spool_time_constant(), FlowLawOptions{}.rig.tau);
  EXPECT_LT(detector.spool_time_constant(), 0.0025);
  EXPECT_LT(o.max_score, detector.raise_threshold());
  EXPECT_GT(o.first_raise, kOnset);
  EXPECT_LT(o.first_raise, kOnset + 10.0);
  std::printf("lag learned %.2f ms, raised %.1f s after the onset\n",
              1e3 * detector.spool_time_constant(), o.first_raise - kOnset);
}

// A valve slower than the stated one (12 ms against the table's 2.5 ms, within MODEL.md's
// 1-20 ms of other rigs). With the stated lag every step's flow lands in the wrong block and the
// fit is poor: its learned spread hides a 1e-12 leak for a minute. The learned lag lands within
// a rung of the ladder, nothing raises before the leak and it is found within 10 s. A state saved
// while the ladder is still weighed decides the same.
TEST(FlowLaw, LearnsTheSpoolLagOfAValveItWasNotToldOf) {
  constexpr double kOnset = 200.0;
  sim::Scenario s = program(17, {phase(sim::PhaseKind::steps, 0.0)}, 300.0);
  s.params.tau = 0.012;
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, kOnset, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions stated;
  stated.learn_spool_time_constant = false;
  FlowLawDetector fixed = make(stated);
  const Outcome f = run(fixed, capture, kOnset);
  EXPECT_DOUBLE_EQ(fixed.spool_time_constant(), stated.rig.tau);
  std::printf("stated lag: first raise %.1f s after the onset\n", f.first_raise - kOnset);
  EXPECT_TRUE(f.first_raise < 0.0 || f.first_raise - kOnset > 60.0);

  FlowLawDetector learning = make();
  const std::size_t split = 40 * 500 + 3 * kStep;  // learning, inside a block
  run(learning, capture, kOnset, 0, split);
  EXPECT_TRUE(std::isnan(learning.spool_time_constant()));
  const DetectorState saved = learning.export_state();
  FlowLawDetector restored = make();
  restored.import_state(saved);
  EXPECT_EQ(restored.export_state(), saved);
  const Outcome a = run(learning, capture, kOnset, split);
  const Outcome b = run(restored, capture, kOnset, split);
  EXPECT_GT(a.learned_at, 0.0);
  EXPECT_NEAR(std::log2(learning.spool_time_constant() / 0.012), 0.0, 1.0 / 3.0 + 1e-9);
  EXPECT_LT(a.max_score, learning.raise_threshold());
  ASSERT_GT(a.first_raise, 0.0);
  EXPECT_LT(a.first_raise - kOnset, 10.0);
  EXPECT_EQ(learning.spool_time_constant(), restored.spool_time_constant());
  EXPECT_EQ(a.first_raise, b.first_raise);
  EXPECT_EQ(a.last.score, b.last.score);
  EXPECT_EQ(learning.export_state(), restored.export_state());
}

// A rig told its description that hunts around its set points (MODEL.md "Other rigs": a 26 mm
// bore, no spring, 62 kg against 4460 N s/m, a 1.5e-7 valve lagging 17 ms, 21 MPa; drawn by
// `leakmon evaluate --rigs other --seed 2411`, run 21) never settles: its turning points pass
// at no speed with the valve open, p1 + p2 - pt there a few per cent off the supply. Read as the
// supply at every such hop, the estimate stepped between 20.9 and 21.6 MPa, and each step put
// a residual with the load's sign into the blocks: healthy, the flow balance raised. The supply
// is read only after `supply_rest_seconds` of rest.
TEST(FlowLaw, AHuntingRigsTurningPointsAreNoSupplyReading) {
  sim::Scenario s = program(21, {phase(sim::PhaseKind::steps, 0.0)}, 420.0);
  sim::Parameters& rig = s.params;
  rig.D = 0.0259775;
  rig.d = 0.0141154;
  rig.L = 0.85318;
  rig.V_dead = 1.46842e-05;
  rig.V_line = 7.8356e-05;
  rig.ps = 2.11542e+07;
  rig.pt = 416222.0;
  rig.beta = 7.64502e+08;
  rig.m = 61.8257;
  rig.b = 4457.24;
  rig.K_s = 0.0;
  rig.Kv = 1.45748e-07;
  rig.tau = 0.0168162;
  rig.C_n = 2.69563e-13;
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions options;
  options.rig = rig;
  const double valve_share = rig.Kv / sim::Parameters::nominal().Kv;  // as the factory scales
  options.design_leak *= valve_share;
  options.min_leak *= valve_share;
  // Without a spring its loads at rest are all near zero and its hunting steps' load term is
  // nearly the volumes' mix (share 0.035): the wait for rest loads or identifying motion never
  // ends on it (docs/detection.md). The supply reading is what this test is about.
  options.min_rest_loads = 0.0;
  FlowLawOptions every_still_hop = options;
  every_still_hop.supply_rest_seconds = 0.0;
  every_still_hop.supply_motion_seconds = 0.0;  // that build read no supply in motion either
  FlowLawDetector before = make(every_still_hop);
  const Outcome b = run(before, capture, 0.0);
  FlowLawDetector settled = make(options);
  const Outcome a = run(settled, capture, 1e9);
  std::printf("every still hop read: first raise at %.1f s; settled rests only: max score %.2f\n",
              b.first_raise, a.max_score);
  EXPECT_GT(b.first_raise, 0.0);  // the test's rig is the one that raised
  EXPECT_GT(a.learned_at, 0.0);
  EXPECT_LT(a.max_score, settled.raise_threshold());
}

// Layout 6 read the supply at settled rests only: a state it wrote loads reading it so and
// decides as that build did, here on a 14 MPa rig (stated 17.2) running a sine that never rests.
TEST(FlowLaw, LayoutSixReadsTheSupplyAtRestOnlyAsItsBuildDid) {
  sim::Scenario s = program(23, {sine(0.0, 0.7, 0.02)}, 200.0);
  s.params.ps = 14e6;
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions at_rest_only;
  at_rest_only.supply_motion_seconds = 0.0;
  at_rest_only.learn_tank_pressure = false;         // added in layout 8
  for (const double cut_seconds : {30.0, 150.0}) {  // learning, judging
    FlowLawDetector old_build = make(at_rest_only);
    const std::size_t split = static_cast<std::size_t>(cut_seconds * 500.0) + 3 * kStep;
    run(old_build, capture, 1e9, 0, split);
    const DetectorState layout_six = as_layout(old_build.export_state(), 6, [](const auto& key) {
      return key.rfind("supply_motion.", 0) == 0;  // added in layout 7
    });
    FlowLawDetector updated = make();
    updated.import_state(layout_six);
    const Outcome a = run(old_build, capture, 1e9, split);
    const Outcome b = run(updated, capture, 1e9, split);
    EXPECT_EQ(a.last.score, b.last.score);
    EXPECT_EQ(a.max_score, b.max_score);
    EXPECT_EQ(old_build.supply(), updated.supply());
    EXPECT_DOUBLE_EQ(updated.supply(), 17.2e6);  // never read: the stated supply
  }
  // A detector of this build reads it in the sine.
  FlowLawDetector now = make();
  run(now, capture, 1e9);
  EXPECT_NEAR(now.supply(), 14e6, 0.02 * 14e6);
}

// A rig not described (run 2 of `evaluate --rigs other --conditions programs --seed 2611`: a 70 mm
// bore at 12.7 MPa) whose tank sits at 0.76 MPa, the table's being 0.1: the supply is read from the
// chambers as ps + pt, so both lands' drops come out 0.66 MPa too large and the orifice law bends
// with the load's sign as a leak's flow does (22 raises in that run; none told only its tank
// pressure; docs/detection.md). Here its steps, a sweep and two sines.
sim::Scenario untold_rig_with_its_tank_high() {
  sim::Phase sweep = phase(sim::PhaseKind::sweep, 180.0);
  sweep.F0 = 0.31;
  sweep.F1 = 3.27;
  sweep.A = 0.0123;
  sim::Scenario s = program(261107835,
                            {phase(sim::PhaseKind::steps, 250.0), sweep, sine(200.0, 1.82, 0.0103),
                             sine(0.0, 2.39, 0.0255)},
                            700.0);
  s.controller = sim::ControllerKind::basic;
  sim::Parameters& rig = s.params;
  rig.D = 0.0698003;
  rig.d = 0.0423161;
  rig.L = 0.136693;
  rig.V_dead = 5.41744e-06;
  rig.V_line = 0.000161793;
  rig.ps = 12.6721e6;
  rig.pt = 0.757244e6;
  rig.beta = 1.20141e9;
  rig.m = 115.393;
  rig.b = 967.337;
  rig.K_s = 228696.0;
  rig.Kv = 1.83819e-06;
  rig.tau = 0.00914335;
  rig.C_n = 9.95316e-13;
  return s;
}

// Learned on its steps, the tank offset's coefficient gives the rig's tank pressure. Given the
// rig's values, its tank stated right (and still asked to learn it, as the factory does not when
// `tank_pressure` is stated), the fitted offset lies within its noise and is not kept: the model
// is the one learned without the regressor, to the bit.
TEST(FlowLaw, ARigNotDescribedLearnsItsTankPressureAndOneStatedRightKeepsIt) {
  const sim::Scenario scenario = untold_rig_with_its_tank_high();
  const capture::Capture capture = sim::simulate(scenario);
  FlowLawDetector untold = make();
  const Outcome a = run(untold, capture, 1e9);
  const FlowLawOptions stated;
  const double tank = stated.rig.pt + untold.coefficients()[6] * stated.rig.ps;
  std::printf("not told: the tank at %.3f MPa (the rig's %.3f)\n", tank / 1e6,
              scenario.params.pt / 1e6);
  EXPECT_GT(a.learned_at, 0.0);
  EXPECT_NEAR(tank, scenario.params.pt, 0.15e6);

  FlowLawOptions told;
  told.rig = scenario.params;
  const double valve_share = told.rig.Kv / sim::Parameters::nominal().Kv;  // as the factory scales
  told.design_leak *= valve_share;
  told.min_leak *= valve_share;
  FlowLawOptions told_without = told;
  told_without.learn_tank_pressure = false;
  FlowLawDetector with = make(told), without = make(told_without);
  const Outcome w = run(with, capture, 1e9);
  const Outcome wo = run(without, capture, 1e9);
  EXPECT_GT(w.learned_at, 0.0);
  EXPECT_EQ(with.coefficients()[6], 0.0);
  EXPECT_EQ(with.coefficients(), without.coefficients());
  EXPECT_EQ(w.max_score, wo.max_score);
  EXPECT_EQ(w.last.score, wo.last.score);
}

// The old build's layout (1: the stated lag only) loads with the stated lag chosen and decides
// as a detector that never learned the lag.
TEST(FlowLaw, LayoutOneLoadsWithTheStatedLagAndDecidesAsItDid) {
  sim::Scenario s = program(19, {phase(sim::PhaseKind::steps, 0.0)}, 140.0);
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, 100.0, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions options;
  options.learning.learn_seconds = 40.0;
  // A state saved while learning learns its range in this build: left out here, where what is
  // compared is the lag (LayoutFiveLoadsWithoutARangeAndJudgesEveryBlock tests the range).
  options.max_leverage_ratio = 0.0;
  FlowLawOptions stated = options;
  stated.learn_spool_time_constant = false;
  stated.learn_null_offset = false;
  stated.learn_tank_pressure = false;
  for (const double cut_seconds : {30.0, 80.0}) {  // learning, judging
    FlowLawDetector old_build = make(stated);
    const std::size_t split = static_cast<std::size_t>(cut_seconds * 500.0) + 3 * kStep;
    run(old_build, capture, 1e9, 0, split);
    // What the build before the ladder wrote: one spool, one flow per sample and block.
    const DetectorState current = old_build.export_state();
    DetectorState layout_one("flow_law", 1);
    for (const auto& [key, values] : current.entries()) {
      if (key == "learned.y_tau" || key == "tau.index" || key == "still_hops") continue;
      if (added_in_layout_five(key) || added_in_layout_eight(key)) continue;
      if (key == "spool.openings" || key == "sample.flows" || key == "block.flows") {
        const std::string single = key == "spool.openings" ? "spool.opening"
                                   : key == "sample.flows" ? "sample.flow"
                                                           : "block.flow";
        layout_one.put(single, values[FlowLawDetector::kStatedTau]);
        continue;
      }
      layout_one.put(key, values);
    }
    FlowLawDetector updated = make(options);
    updated.import_state(layout_one);
    EXPECT_DOUBLE_EQ(updated.spool_time_constant(), options.rig.tau);
    const Outcome a = run(old_build, capture, 100.0, split);
    const Outcome b = run(updated, capture, 100.0, split);
    EXPECT_GT(a.first_raise, 100.0);
    EXPECT_EQ(a.first_raise, b.first_raise);
    EXPECT_EQ(a.last.score, b.last.score);
    EXPECT_EQ(a.last.leak_coefficient, b.last.leak_coefficient);
  }
}

// Layout 3 did not tell blocks at rest from moving ones: its learning blocks load as moving and
// its block in progress too. A state saved while waiting through a hold still waits (its hold
// blocks give no rest loads) and learns once the steps come; one saved while judging decides as
// the build that wrote it.
TEST(FlowLaw, LayoutThreeLoadsItsBlocksAsMoving) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::hold, 40.0),
                                    phase(sim::PhaseKind::steps, 0.0)};
  phases[0].X = 0.02;
  sim::Scenario s = program(13, phases, 140.0);
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, 115.0, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions options;
  options.learning.learn_seconds = 30.0;
  FlowLawOptions layout_four = options;
  layout_four.learn_null_offset = false;
  layout_four.learn_tank_pressure = false;
  layout_four.max_leverage_ratio = 0.0;             // nor a learned range (layout 6)
  for (const double cut_seconds : {38.0, 100.0}) {  // waiting in the hold, judging
    FlowLawDetector writer = make(layout_four);
    const std::size_t split = static_cast<std::size_t>(cut_seconds * 500.0) + 3 * kStep;
    run(writer, capture, 1e9, 0, split);
    const DetectorState current = writer.export_state();
    DetectorState layout_three("flow_law", 3);
    for (const auto& [key, values] : current.entries()) {
      if (key == "learned.moving" || key == "block.max_speed") continue;
      if (added_in_layout_five(key) || added_in_layout_eight(key)) continue;
      layout_three.put(key, values);
    }
    FlowLawDetector updated = make(options);
    updated.import_state(layout_three);
    const DetectorState converted = updated.export_state();
    const auto& moving = converted.get_list("learned.moving");
    EXPECT_EQ(moving.size(), current.get_list("learned.moving").size());
    EXPECT_TRUE(std::all_of(moving.begin(), moving.end(), [](double m) { return m == 1.0; }));
    EXPECT_TRUE(std::isnan(converted.get("block.max_speed")));
    if (cut_seconds < 40.0) {
      EXPECT_FALSE(moving.empty());
      EXPECT_TRUE(updated.waiting_for_excitation());
      const Outcome b = run(updated, capture, 115.0, split);
      EXPECT_GT(b.learned_at, 40.0);
      EXPECT_GT(b.first_raise, 115.0);
    } else {
      EXPECT_TRUE(moving.empty());  // learned: no learning blocks kept
      const Outcome a = run(writer, capture, 115.0, split);
      const Outcome b = run(updated, capture, 115.0, split);
      EXPECT_GT(b.first_raise, 115.0);
      EXPECT_EQ(a.first_raise, b.first_raise);
      EXPECT_EQ(a.last.score, b.last.score);
      EXPECT_EQ(a.last.leak_coefficient, b.last.leak_coefficient);
    }
  }
}

// Layout 4 had no null-offset regressor. A state saved while learning keeps its blocks, which
// lack the regressor, and learns without it as the build that wrote it (on a biased valve too);
// one saved while judging decides as that build; one saved before its first learning block
// learns the null offset.
TEST(FlowLaw, LayoutFourLearnsWithoutTheNullOffsetOnlyWhenItHadLearningBlocks) {
  sim::Scenario s = program(29, {phase(sim::PhaseKind::steps, 0.0)}, 140.0);
  s.effects.valve_bias = sim::ValveBias{0.08};
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, 100.0, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions options;
  options.learning.learn_seconds = 40.0;
  FlowLawOptions layout_four = options;
  layout_four.learn_null_offset = false;
  layout_four.learn_tank_pressure = false;
  for (const double cut_seconds : {0.5, 30.0, 80.0}) {  // settling, learning, judging
    FlowLawDetector writer = make(layout_four);
    const std::size_t split = static_cast<std::size_t>(cut_seconds * 500.0) + 3 * kStep;
    run(writer, capture, 1e9, 0, split);
    const DetectorState current = writer.export_state();
    DetectorState saved("flow_law", 4);
    for (const auto& [key, values] : current.entries()) {
      if (!added_in_layout_five(key) && !added_in_layout_eight(key)) saved.put(key, values);
    }
    FlowLawDetector updated = make(options);
    updated.import_state(saved);
    const DetectorState converted = updated.export_state();
    const auto& offsets = converted.get_list("learned.null_offset");
    EXPECT_EQ(offsets.size(), current.get_list("learned.t").size());
    EXPECT_TRUE(std::all_of(offsets.begin(), offsets.end(), [](double v) { return v == 0.0; }));
    const Outcome a = run(writer, capture, 100.0, split);
    const Outcome b = run(updated, capture, 100.0, split);
    EXPECT_GT(b.first_raise, 100.0);
    EXPECT_LT(b.max_score, updated.raise_threshold());
    if (cut_seconds < 1.0) {
      EXPECT_TRUE(offsets.empty());
      EXPECT_EQ(converted.get("null_offset.fit"), 1.0);
      // At one temperature the offset's flow is nearly a mix of the load term and the offset's
      // (-0.0045 here for -0.008): fitted, with the offset's sign.
      EXPECT_LT(updated.coefficients()[5], -0.002);
      EXPECT_EQ(writer.coefficients()[5], 0.0);
    } else {
      EXPECT_EQ(converted.get("null_offset.fit"), cut_seconds < 40.0 ? 0.0 : 1.0);
      EXPECT_EQ(updated.coefficients()[5], 0.0);
      EXPECT_EQ(a.learned_at, b.learned_at);
      EXPECT_EQ(a.first_raise, b.first_raise);
      EXPECT_EQ(a.last.score, b.last.score);
      EXPECT_EQ(a.last.leak_coefficient, b.last.leak_coefficient);
    }
  }
}

// Layout 7 had no tank-offset regressor. As layout 4's null offset: a state saved while learning
// or judging decides as the build that wrote it (its learned range without the new axis), one
// saved before its first learning block learns the tank offset.
TEST(FlowLaw, LayoutSevenLearnsWithoutTheTankOffsetOnlyWhenItHadNoLearningBlocks) {
  const capture::Capture capture = sim::simulate(untold_rig_with_its_tank_high());
  FlowLawOptions layout_seven;
  layout_seven.learn_tank_pressure = false;
  for (const double cut_seconds : {0.0, 30.0, 150.0}) {  // no block yet, learning, judging
    FlowLawDetector writer = make(layout_seven);
    const std::size_t split = static_cast<std::size_t>(cut_seconds * 500.0) + 3 * kStep;
    run(writer, capture, 1e9, 0, split);
    const DetectorState saved =
        as_layout(writer.export_state(), 7, [](const std::string&) { return false; });
    FlowLawDetector updated = make();
    updated.import_state(saved);
    const DetectorState converted = updated.export_state();
    EXPECT_EQ(converted.version(), FlowLawDetector::kStateVersion);
    EXPECT_EQ(
        converted.get_list("range.inverse_normal").size(),
        static_cast<std::size_t>(FlowLawDetector::kRegressors * FlowLawDetector::kRegressors));
    const Outcome a = run(writer, capture, 1e9, split);
    const Outcome b = run(updated, capture, 1e9, split);
    if (cut_seconds < 1.0) {
      EXPECT_EQ(converted.get("tank_offset.fit"), 1.0);
      EXPECT_GT(updated.coefficients()[6], 0.0);  // learned: the rig's tank lies above the stated
      EXPECT_EQ(writer.coefficients()[6], 0.0);
    } else {
      EXPECT_EQ(converted.get("tank_offset.fit"), 0.0);
      EXPECT_EQ(updated.coefficients()[6], 0.0);
      EXPECT_EQ(a.learned_at, b.learned_at);
      EXPECT_EQ(a.max_score, b.max_score);
      EXPECT_EQ(a.last.score, b.last.score);
      EXPECT_EQ(a.last.leak_coefficient, b.last.leak_coefficient);
    }
  }
}

// Layout 5 kept no learned range: loaded, it judges every block as its build did, on the state's
// own coefficients; after a reset it learns the range again.
TEST(FlowLaw, LayoutFiveLoadsWithoutARangeAndJudgesEveryBlock) {
  const capture::Capture capture = triangle_then_fast_sweep();
  FlowLawOptions layout_five;
  layout_five.max_leverage_ratio = 0.0;
  layout_five.learn_tank_pressure = false;
  FlowLawDetector writer = make(layout_five);
  const std::size_t split = 160 * 500 + 3 * kStep;
  run(writer, capture, 1e9, 0, split);
  const DetectorState current = writer.export_state();
  DetectorState saved("flow_law", 5);
  for (const auto& [key, values] : current.entries()) {
    if (!key.starts_with("range.") && !added_in_layout_eight(key)) saved.put(key, values);
  }
  FlowLawDetector updated = make();
  updated.import_state(saved);
  EXPECT_TRUE(std::isnan(updated.max_learned_leverage()));
  const Outcome a = run(writer, capture, 1e9, split);
  const Outcome b = run(updated, capture, 1e9, split);
  EXPECT_EQ(updated.blocks_not_judged_outside_learned_range(), 0u);
  EXPECT_EQ(a.last.score, b.last.score);
  EXPECT_EQ(a.last.judged, b.last.judged);
  updated.reset();
  const Outcome again = run(updated, capture, 1e9);
  EXPECT_GT(again.learned_at, 0.0);
  EXPECT_GT(updated.max_learned_leverage(), 0.0);
  EXPECT_GT(updated.blocks_not_judged_outside_learned_range(), 0u);
}

// Learning (and waiting for excitation), detection and the alarm allocate nothing; reset()
// starts learning again.
TEST(FlowLaw, UpdateAllocatesNothingAndResetStartsLearningAgain) {
  std::vector<sim::Phase> phases = {phase(sim::PhaseKind::hold, 20.0),
                                    phase(sim::PhaseKind::steps, 0.0)};
  phases[0].X = 0.01;
  sim::Scenario s = program(11, phases, 90.0);
  s.effects.internal_leakage = sim::InternalLeakage{2e-12, 70.0, 0.0};
  const capture::Capture capture = sim::simulate(s);
  FlowLawOptions options;
  options.learning.learn_seconds = 15.0;  // over in the hold: waits, then learns on the steps
  FlowLawDetector detector = make(options);
  std::uint64_t allocations = 0;
  const Outcome o = run(detector, capture, 70.0, 0, 0, &allocations);
  EXPECT_EQ(allocations, 0u);
  EXPECT_TRUE(o.waited);
  EXPECT_GT(o.first_raise, 70.0);
  detector.reset();
  const Outcome again = run(detector, capture, 1e9, 0, 50 * kStep);
  EXPECT_TRUE(again.last.learning);
  EXPECT_FALSE(std::isnan(again.last.learning_hops_left));
}

// Reachable through the registry by name, needs u and x, and is the default with them (issue 23:
// it judges in every program, where flow_balance judges only at rest).
// A tank pressure stated (the rig's `tank_pressure`, or the detector's option) is taken as it is;
// the table's is learned where the data tell it otherwise; `learn_tank_pressure` overrides both.
TEST(FlowLaw, AStatedTankPressureIsTakenAsItIs) {
  const sim::RigDescription paper = sim::RigDescription::paper();
  const sim::RigDescription stated =
      sim::read_rig(config::ConfigNode::load_string("tank_pressure: 0.4e6\n", "rig.yaml"));
  const auto learns = [](const std::string& options, const sim::RigDescription& rig) {
    const auto node = config::ConfigNode::load_string(options, "f.yaml");
    const auto detector = make_detector("flow_law", {true, true, true, true}, kHop, &node, &rig);
    return detector->export_state().get("tank_offset.fit") != 0.0;
  };
  EXPECT_TRUE(learns("{}\n", paper));
  EXPECT_FALSE(learns("{}\n", stated));
  EXPECT_FALSE(learns("tank_pressure: 0.4e6\n", paper));
  EXPECT_TRUE(learns("learn_tank_pressure: true\n", stated));
  EXPECT_FALSE(learns("learn_tank_pressure: false\n", paper));
}

TEST(FlowLaw, RegistryKind) {
  AvailableSignals all;
  all.p1 = all.p2 = all.u = all.x = true;
  EXPECT_EQ(make_detector("flow_law", all, kHop, nullptr, nullptr)->name(), "flow_law");
  EXPECT_EQ(default_detector_kind(all), "flow_law");
  AvailableSignals pressures;
  pressures.p1 = pressures.p2 = true;
  EXPECT_THROW(make_detector("flow_law", pressures, kHop, nullptr, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace leakmon::detect
