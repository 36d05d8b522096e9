// The sequential-test core the detectors share (issue 26): the ring, the learning clock, the
// drift reference, the supply tracker, the block CUSUM with its take-back history, each saving
// itself under named keys. The detectors' own tests (and legacy_state_test.cpp, to the bit
// against the build before the core) cover them in use; these pin down each rule alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "detect/cusum.hpp"
#include "detect/detector_state.hpp"
#include "detect/drift_reference.hpp"
#include "detect/factory.hpp"
#include "detect/feature_test.hpp"
#include "detect/learning_schedule.hpp"
#include "detect/ring.hpp"
#include "detect/supply_tracker.hpp"
#include "tests/detect/synthetic_pressures.hpp"
#include "tests/detect/synthetic_rig.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::detect {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool same_bits(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

// A piece's state through text and back, as the daemon's state file carries it.
template <class Piece>
void through_text(const Piece& from, Piece& to, std::string_view prefix = "piece") {
  DetectorState state("probe", 1);
  from.save(state, prefix);
  to.restore(DetectorState::parse(state.text()), prefix);
}

struct Sample {
  double t, v;
};
constexpr std::array<RecordField<Sample>, 2> kSampleFields = {record_field<&Sample::t>("t"),
                                                              record_field<&Sample::v>("v")};

// ---- Ring ----

TEST(Ring, KeepsTheNewestAndOverwritesTheOldest) {
  Ring<int> ring(3);
  EXPECT_TRUE(ring.empty());
  for (int i = 1; i <= 2; ++i) ring.push(i);
  EXPECT_EQ(ring.size(), 2u);
  EXPECT_FALSE(ring.full());
  EXPECT_EQ(ring.newest(), 2);
  EXPECT_EQ(ring.oldest(), 1);
  for (int i = 3; i <= 5; ++i) ring.push(i);
  EXPECT_TRUE(ring.full());
  EXPECT_EQ(ring.newest(0), 5);
  EXPECT_EQ(ring.newest(2), 3);
  EXPECT_EQ(ring.oldest(0), 3);
  EXPECT_EQ(ring.oldest(2), 5);
  // Slot order, not age: 4 and 5 overwrote the first two slots.
  const std::vector<int> slots(ring.stored().begin(), ring.stored().end());
  EXPECT_EQ(slots, (std::vector<int>{4, 5, 3}));
  ring.clear();
  EXPECT_TRUE(ring.empty());
  EXPECT_TRUE(ring.stored().empty());
}

TEST(Ring, OfNoCapacityKeepsNothing) {
  Ring<int> ring(0);
  ring.push(1);
  EXPECT_TRUE(ring.empty());
  EXPECT_TRUE(ring.full());
}

TEST(Ring, PushAllocatesNothing) {
  Ring<Sample> ring(100);
  test::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) ring.push({static_cast<double>(i), 0.5 * i});
  EXPECT_EQ(scope.count(), 0u);
}

TEST(Ring, SavedAndRestoredKeepsItsSlots) {
  for (const int pushed : {0, 4, 7, 23}) {
    Ring<Sample> a(7), b(7);
    for (int i = 0; i < pushed; ++i) a.push({0.1 * i, std::sqrt(i + 0.5)});
    DetectorState state("probe", 1);
    save_ring(state, "ring", a, kSampleFields);
    EXPECT_EQ(state.get_list("ring.t").size(), a.size());
    restore_ring(DetectorState::parse(state.text()), "ring", b, kSampleFields);
    ASSERT_EQ(b.size(), a.size());
    EXPECT_EQ(b.next_slot(), a.next_slot());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_TRUE(same_bits(a.stored()[i].v, b.stored()[i].v));
    }
    a.push({9.0, 9.0});
    b.push({9.0, 9.0});
    EXPECT_EQ(a.oldest().t, b.oldest().t) << pushed;
  }
}

TEST(Ring, RefusesAStateThatDoesNotFit) {
  Ring<Sample> a(5);
  for (int i = 0; i < 3; ++i) a.push({1.0 * i, 0.0});
  DetectorState state("probe", 1);
  save_ring(state, "ring", a, kSampleFields);
  Ring<Sample> other(6);
  EXPECT_THROW(restore_ring(state, "ring", other, kSampleFields), StateError) << "capacity";
  DetectorState skewed = state;
  skewed.put_count("ring.next", 1);  // three records, not full: the next slot is the fourth
  EXPECT_THROW(restore_ring(skewed, "ring", a, kSampleFields), StateError);
  DetectorState ragged = state;
  ragged.put("ring.v", std::vector<double>{1.0, 2.0});
  EXPECT_THROW(restore_ring(ragged, "ring", a, kSampleFields), StateError);
}

// ---- LearningClock ----

TEST(LearningClock, SettlesThenLearnsForTheScheduledHops) {
  LearningClock clock(LearningSchedule{0.08, 0.2}, 0.04);  // 2 settle hops, 5 learning hops
  EXPECT_FALSE(clock.count_hop());
  EXPECT_EQ(clock.hops_left(), 6.0);
  EXPECT_FALSE(clock.count_hop());
  for (std::size_t hop = 0; hop < 5; ++hop) {
    EXPECT_TRUE(clock.count_hop());
    EXPECT_EQ(clock.learning_hop(), hop);
    EXPECT_EQ(clock.period_over(), hop == 4);
  }
  EXPECT_EQ(clock.hops_left(), 0.0);
  clock.set_learned();
  LearningClock restored(LearningSchedule{0.08, 0.2}, 0.04);
  through_text(clock, restored);
  EXPECT_TRUE(restored.learned());
  EXPECT_TRUE(restored.count_hop());
  EXPECT_TRUE(restored.period_over());
}

// ---- DriftReference ----

DriftReferenceOptions drift_options(double bound, bool shrink) {
  DriftReferenceOptions o;
  o.guard_seconds = 10.0;
  o.window_seconds = 40.0;
  o.keep_seconds = 60.0;
  o.block_seconds = 1.0;
  o.bound = bound;
  o.shrink_slope = shrink;
  o.slope_needs_full_window = shrink;
  return o;
}

TEST(DriftReference, NothingFewBlocksALevelThenTheLineExtrapolated) {
  DriftReference drift(drift_options(1.0, false));
  const double now = 100.0;
  EXPECT_EQ(drift.reference(now, kNaN, false, kNaN), 0.0);
  // Blocks of a residual drifting at 1e-3 per second; the window is [50, 90].
  auto residual = [](double t) { return 0.2 + 1e-3 * (t - 100.0); };
  for (double t = 50.0; t < 52.5; t += 1.0) drift.add(t, residual(t));
  EXPECT_NEAR(drift.reference(now, kNaN, false, kNaN), residual(51.0), 1e-12) << "their level";
  for (double t = 53.0; t <= 99.0; t += 1.0) drift.add(t, residual(t));
  // The blocks of the guard (after 90) are not in it; the line through the window is.
  EXPECT_NEAR(drift.reference(now, kNaN, false, kNaN), residual(now), 1e-12);
  EXPECT_NEAR(drift.reference(now, kNaN, true, kNaN), residual(70.0), 1e-12) << "level only";
  drift.clear();
  EXPECT_EQ(drift.reference(now, kNaN, false, kNaN), 0.0);
}

TEST(DriftReference, TheExtrapolationIsBounded) {
  DriftReference drift(drift_options(0.01, false));
  for (double t = 50.0; t <= 90.0; t += 1.0) drift.add(t, 0.05 * (t - 70.0));
  // The level at the window's centre is 0; the line at 100 is 1.5, bounded to 0.01.
  EXPECT_NEAR(drift.reference(100.0, kNaN, false, kNaN), 0.01, 1e-12);
}

// flow_balance's reference is a slope on the leak term: blocks weigh with its square and the
// residual is its multiple.
TEST(DriftReference, AScaledReferenceIsTheLevelPerUnitOfScale) {
  DriftReference drift(drift_options(1.0, false));
  double scale = 0.3;
  for (double t = 50.0; t <= 90.0; t += 1.0, scale = -scale * 1.1) drift.add(t, 0.4 * scale, scale);
  EXPECT_NEAR(drift.reference(100.0, kNaN, false, kNaN), 0.4, 1e-12);
}

// The index's reference shrinks a slope the window barely identifies towards the level, and
// needs blocks over 0.9 of the window before it fits one.
TEST(DriftReference, ANoisySlopeIsShrunkAClearOneFollowed) {
  DriftReference drift(drift_options(1.0, true));
  for (double t = 50.0; t <= 90.0; t += 1.0) drift.add(t, 1e-3 * (t - 100.0));
  const double clear = drift.reference(100.0, 1e-6, false, kNaN);
  const double noisy = drift.reference(100.0, 10.0, false, kNaN);
  const double level = drift.reference(100.0, 1e-6, true, kNaN);
  EXPECT_NEAR(clear, 0.0, 1e-9) << "followed to now";
  EXPECT_NEAR(noisy, level, 1e-5) << "shrunk to the level";
  EXPECT_GT(std::abs(clear - level), 0.02);
  DriftReference short_span(drift_options(1.0, true));
  for (double t = 70.0; t <= 90.0; t += 0.5) short_span.add(t, 1e-3 * (t - 100.0));
  EXPECT_NEAR(short_span.reference(100.0, 1e-6, false, kNaN), -0.02, 1e-12) << "level";
}

// Blocks that stop early in the window (the first program left for another one the feature
// test does not judge) span less than it however early the first of them lies: their level, not
// their slope carried across the gap to now, and held there however long the gap lasts. A
// reference without hold_across_gaps (a state of a build before it) slides on as it did.
TEST(DriftReference, BlocksThatStopGiveTheirLevelAndHoldIt) {
  DriftReferenceOptions options = drift_options(1.0, true);
  options.hold_across_gaps = true;
  DriftReference drift(options);
  DriftReference before(drift_options(1.0, true));
  // The window at 100 is [50, 90]; the blocks span 50-62, then nothing.
  const auto residual = [](double t) { return 1e-3 * (t - 56.0); };
  for (double t = 50.0; t <= 62.0; t += 0.5) {
    drift.add(t, residual(t));
    before.add(t, residual(t));
  }
  EXPECT_NEAR(drift.reference(100.0, 1e-6, false, kNaN), 0.0, 1e-12) << "their level";
  EXPECT_NEAR(before.reference(100.0, 1e-6, false, kNaN), 0.044, 1e-9) << "the slope carried";
  EXPECT_NEAR(drift.reference(1000.0, 1e-6, false, kNaN), 0.0, 1e-12) << "held";
  EXPECT_EQ(before.reference(1000.0, 1e-6, false, kNaN), 0.0) << "slid past them";
  // While they age out of the sliding window, its level is that of the last few.
  EXPECT_NEAR(before.reference(110.0, 1e-6, false, kNaN), residual(61.0), 1e-12);
  EXPECT_NEAR(drift.reference(110.0, 1e-6, false, kNaN), 0.0, 1e-12);
  // Blocks again at the window's end: the line through both is followed.
  for (double t = 86.0; t <= 90.0; t += 0.5) drift.add(t, residual(t));
  EXPECT_NEAR(drift.reference(100.0, 1e-6, false, kNaN), 0.044, 1e-9) << "the line";
}

// After a re-anchoring the blocks since the step are all the reference there is: the window
// reaches up to the end of the anchoring, inside the guard; with following off, only they count.
TEST(DriftReference, AfterAReAnchoringItsBlocksAreTheReference) {
  DriftReferenceOptions options = drift_options(1.0, true);
  options.window_seconds = 0.0;
  DriftReference drift(options);
  for (double t = 95.0; t <= 99.0; t += 1.0) drift.add(t, 0.3);
  EXPECT_EQ(drift.reference(100.0, 0.1, false, kNaN), 0.0) << "following off";
  EXPECT_NEAR(drift.reference(100.0, 0.1, false, 99.5), 0.3, 1e-12);
}

TEST(DriftReference, SavedAndRestoredGivesTheSameBits) {
  DriftReference a(drift_options(0.05, true)), b(drift_options(0.05, true));
  std::mt19937_64 random(3);
  std::normal_distribution<double> normal;
  for (double t = 0.0; t < 120.0; t += 1.0) a.add(t, 0.01 * normal(random) + 1e-4 * t);
  through_text(a, b, "drift");
  EXPECT_TRUE(
      same_bits(a.reference(120.0, 0.01, false, kNaN), b.reference(120.0, 0.01, false, kNaN)));
  DriftReference small(drift_options(0.05, true));
  DriftReferenceOptions other = drift_options(0.05, true);
  other.keep_seconds = 20.0;
  DriftReference shorter(other);
  DetectorState state("probe", 1);
  a.save(state, "drift");
  EXPECT_THROW(shorter.restore(state, "drift"), StateError) << "a window of another length";
}

// ---- SupplyTracker ----

SupplyTrackerOptions supply_options(SupplyTrackerOptions::StepRule rule, std::size_t confirm) {
  SupplyTrackerOptions o;
  o.configured = 17.2e6;
  o.rule = rule;
  o.confirm_readings = confirm;
  o.reading_seconds = 0.04;
  return o;
}

// flow_balance's rule: a reading 2 % of the supply off the estimate is a step at once.
TEST(SupplyTracker, JumpRuleStepsAtOnceAndSmoothsRestReadings) {
  SupplyTracker supply(supply_options(SupplyTrackerOptions::StepRule::jump, 1));
  EXPECT_EQ(supply.estimate(), 17.2e6) << "the configured supply before a reading";
  EXPECT_FALSE(supply.add(1.0, kNaN, false));
  EXPECT_FALSE(supply.add(1.0, 17.0e6, false)) << "the first reading is no step";
  EXPECT_EQ(supply.estimate(), 17.0e6);
  EXPECT_FALSE(supply.add(1.04, 17.1e6, false));
  const double memory = std::exp(-0.04 / kSupplyMemorySeconds);
  EXPECT_DOUBLE_EQ(supply.estimate(), memory * 17.0e6 + (1.0 - memory) * 17.1e6);
  EXPECT_TRUE(supply.settled(1.04));
  EXPECT_TRUE(supply.add(2.0, 16.5e6, false));
  EXPECT_EQ(supply.estimate(), 16.5e6);
  EXPECT_EQ(supply.step_time(), 2.0);
  EXPECT_FALSE(supply.settled(2.0 + kSupplyTransientSeconds - 0.04));
  EXPECT_TRUE(supply.settled(2.0 + kSupplyTransientSeconds));
  EXPECT_FALSE(supply.add(6.0, 16.6e6, true));
  EXPECT_EQ(supply.estimate(), 16.6e6) << "a `ps` reading is the supply";
  supply.resume_after_gap();
  EXPECT_TRUE(std::isnan(supply.step_time()));
  EXPECT_EQ(supply.estimate(), 16.6e6);
}

// The feature test's rule: a rest reading that far off has to persist; a ramp that moves the
// estimate that far from the supply at the last step is a step too.
TEST(SupplyTracker, DriftFromAnchorRuleNeedsPersistenceAndCatchesARamp) {
  SupplyTracker supply(supply_options(SupplyTrackerOptions::StepRule::drift_from_anchor, 10));
  double t = 0.0;
  supply.add(t, 17.2e6, false);
  EXPECT_FALSE(supply.add(t += 0.04, 15e6, false)) << "one odd hop";
  EXPECT_EQ(supply.estimate(), 17.2e6);
  for (int i = 0; i < 8; ++i) EXPECT_FALSE(supply.add(t += 0.04, 15e6, false));
  EXPECT_TRUE(supply.add(t += 0.04, 15e6, false)) << "the tenth in a row";
  EXPECT_EQ(supply.estimate(), 15e6);
  EXPECT_EQ(supply.step_time(), t);
  // A ramp of 0.1 % of the supply per reading: each within the step of the estimate.
  bool stepped = false;
  double reading = 15e6;
  for (int i = 0; i < 200 && !stepped; ++i) {
    reading += 17.2e3;
    stepped = supply.add(t += 0.04, reading, true);
  }
  EXPECT_TRUE(stepped);
  EXPECT_NEAR(supply.estimate() - 15e6, kSupplyStepShare * 17.2e6, 17.2e3 + 1.0);
  supply.set_after_step(100.0, 16e6);
  EXPECT_EQ(supply.estimate(), 16e6);
  EXPECT_EQ(supply.step_time(), 100.0);
  SupplyTracker restored(supply_options(SupplyTrackerOptions::StepRule::drift_from_anchor, 10));
  through_text(supply, restored, "supply");
  EXPECT_EQ(restored.estimate(), 16e6);
  EXPECT_EQ(restored.step_time(), 100.0);
  EXPECT_FALSE(restored.add(101.0, 16.2e6, true)) << "anchored at the set supply";
  EXPECT_TRUE(restored.add(101.04, 16.4e6, true));
}

// ---- BlockCusum ----

TEST(BlockCusum, ClampsAtZeroAndAtItsCap) {
  BlockCusum cusum(5.0);
  EXPECT_EQ(cusum.add(1.0, -3.0), 0.0);
  EXPECT_EQ(cusum.add(2.0, 4.0), 4.0);
  EXPECT_EQ(cusum.normalised(), 0.8);
  EXPECT_EQ(cusum.add(3.0, 100.0), 20.0) << "four thresholds";
}

// The blocks judged after a supply step began (found only later) are taken back: the CUSUM
// returns to its value before the oldest of them.
TEST(BlockCusum, TakesBackTheBlocksJudgedAfterAStep) {
  BlockCusum cusum(10.0, 4);
  cusum.add(1.0, 1.0);  // 1
  cusum.add(2.0, 2.0);  // 3
  cusum.add(3.0, 3.0);  // 6
  cusum.add(4.0, 4.0);  // 10
  cusum.take_back_after(2.5);
  EXPECT_EQ(cusum.value(), 3.0);
  cusum.add(5.0, 1.0);
  cusum.add(6.0, 1.0);
  // Only four blocks are remembered (3, 4, 5, 6): a step before them all takes back to the
  // oldest remembered.
  cusum.take_back_after(0.5);
  EXPECT_EQ(cusum.value(), 3.0);
  cusum.add(7.0, 2.0);
  cusum.take_back_after(7.0);
  EXPECT_EQ(cusum.value(), 5.0) << "nothing judged after 7";
  BlockCusum restored(10.0, 4);
  through_text(cusum, restored, "cusum");
  EXPECT_EQ(restored.value(), 5.0);
  restored.take_back_after(6.5);
  EXPECT_EQ(restored.value(), 3.0);
  cusum.forget_history();
  cusum.take_back_after(0.0);
  EXPECT_EQ(cusum.value(), 5.0) << "a history on another clock is forgotten";
  BlockCusum plain(10.0);
  plain.add(1.0, 4.0);
  plain.take_back_after(0.0);
  EXPECT_EQ(plain.value(), 4.0) << "without a history nothing is taken back";
  BlockCusum longer(10.0, 8);
  DetectorState state("probe", 1);
  cusum.save(state, "cusum");
  EXPECT_THROW(longer.restore(state, "cusum"), StateError);
}

// ---- The threshold (issue 23) ----

// Mean run length to an alarm of a CUSUM of Gaussian log-likelihood-ratio increments
// shift (z - shift / 2), z ~ N(0, 1) (no leak), with threshold h, over `runs` runs.
double mean_run_length(double shift, double h, int runs, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  double total = 0.0;
  for (int run = 0; run < runs; ++run) {
    double sum = 0.0;
    long blocks = 0;
    do {
      ++blocks;
      sum = std::max(0.0, sum + shift * (normal(rng) - shift / 2.0));
    } while (sum < h);
    total += static_cast<double>(blocks);
  }
  return total / runs;
}

// Siegmund's threshold gives the target run length where Lorden's (ln ARL0) overstates it
// several times: the 2-3 nats the pressure-only detectors gave away (docs/detection.md).
TEST(CusumThreshold, SiegmundsGivesTheTargetRunLengthLordensOverstatesIt) {
  std::mt19937_64 rng(23);
  const double block_seconds = 1.6;
  const double per_hour = 3600.0 / (2000.0 * block_seconds);  // ARL0 of 2000 blocks
  const double lorden = cusum_threshold_for(per_hour, block_seconds);
  EXPECT_NEAR(lorden, std::log(2000.0), 1e-12);
  for (const double shift : {0.5, 1.0}) {
    const double h = cusum_threshold_for_shift(per_hour, block_seconds, -shift);
    EXPECT_LT(h, lorden - 1.0) << shift;
    const double arl = mean_run_length(shift, h, 1500, rng);
    EXPECT_GT(arl, 0.8 * 2000.0) << shift;
    EXPECT_LT(arl, 1.25 * 2000.0) << shift;
    EXPECT_GT(mean_run_length(shift, lorden, 300, rng), 2.0 * 2000.0) << shift;
  }
  // The detectors' target (0.05 per hour, 1.6 s blocks): 7.9-8.9 nats against Lorden's 10.7.
  EXPECT_NEAR(cusum_threshold_for_shift(0.05, 1.6, -0.5), 8.06, 0.05);
  EXPECT_NEAR(cusum_threshold_for_shift(0.05, 1.6, -1.0), 8.86, 0.05);
  EXPECT_EQ(cusum_threshold_for_shift(0.05, 1.6, 0.0), cusum_threshold_for(0.05, 1.6));
  EXPECT_EQ(cusum_threshold_for_shift(0.05, 1.6, kNaN), cusum_threshold_for(0.05, 1.6));
}

TEST(BlockCusum, ANewThresholdKeepsTheValueWithinTheNewCap) {
  BlockCusum cusum(10.0);
  cusum.add(1.0, 30.0);
  cusum.set_threshold(5.0);
  EXPECT_EQ(cusum.threshold(), 5.0);
  EXPECT_EQ(cusum.value(), 20.0) << "four thresholds";
  EXPECT_EQ(cusum.normalised(), 4.0);
}

// The feature test takes Siegmund's threshold once it has learned the block spread (where its
// physics asks for it: detail_xcorr's), and a state restored into a fresh test judges against the
// same threshold; a state from the build before keeps Lorden's.
TEST(FeatureTest, LearnsItsThresholdFromTheSpreadAndRestoresIt) {
  FeatureTestOptions options;
  options.learning.settle_seconds = 2.0;
  options.learning.learn_seconds = 90.0;
  FeaturePhysics physics;
  physics.design_shift = std::log1p(-0.12);
  physics.null_shift = 0.0;
  physics.threshold_from_spread = true;
  FeatureTest test(options, physics, 0.04);
  FeaturePhysics lorden_physics = physics;
  lorden_physics.threshold_from_spread = false;
  FeatureTest lorden_test(options, lorden_physics, 0.04);
  const double lorden = cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds);
  EXPECT_EQ(test.cusum_threshold(), lorden);
  test::SyntheticRig rig;
  while (rig.t < 120.0) {
    const Observation o = rig.next();
    test.update(o, std::log(o.index_p1));
    lorden_test.update(o, std::log(o.index_p1));
  }
  EXPECT_EQ(lorden_test.cusum_threshold(), lorden);
  const double learned = test.cusum_threshold();
  EXPECT_LT(learned, lorden - 0.5);
  EXPECT_GT(learned, 0.6 * lorden);
  FeatureTest restored(options, physics, 0.04);
  through_text(test, restored, "test");
  EXPECT_EQ(restored.cusum_threshold(), learned);
  DetectorState saved("probe", 1);
  test.save(saved, "test");
  saved.put("test.threshold.siegmund", 0.0);  // as legacy_state.cpp converts an older state
  FeatureTest older(options, physics, 0.04);
  older.restore(DetectorState::parse(saved.text()), "test");
  EXPECT_EQ(older.cusum_threshold(), lorden);
  restored.reset();
  EXPECT_EQ(restored.cusum_threshold(), lorden);
}

// ---- The real-time rule ----

// The pieces on the worker's path allocate nothing once built, through steps and take-backs
// (the detectors in use: detectors_test.cpp and index_drift_test.cpp, the one-chamber supply
// step included).
TEST(SequentialCore, PiecesAllocateNothingAfterConstruction) {
  DriftReference drift(drift_options(0.05, true));
  SupplyTracker supply(supply_options(SupplyTrackerOptions::StepRule::drift_from_anchor, 10));
  BlockCusum cusum(10.0, 60);
  LearningClock clock(LearningSchedule{}, 0.04);
  std::mt19937_64 random(5);
  std::normal_distribution<double> normal;
  double sink = 0.0;
  test::AllocationScope scope;
  for (int i = 0; i < 20000; ++i) {
    const double t = 0.04 * i;
    clock.count_hop();
    const double reading = (t < 400.0 ? 17.2e6 : 15e6) + 1e4 * normal(random);
    if (supply.add(t, reading, i % 7 == 0)) drift.clear();
    if (i % 20 == 0) {
      drift.add(t, 0.01 * normal(random));
      sink += drift.reference(t, 0.01, false, supply.step_time() + 20.0);
      cusum.add(t, normal(random));
      if (i % 2000 == 0) cusum.take_back_after(t - 10.0);
    }
  }
  EXPECT_EQ(scope.count(), 0u);
  EXPECT_TRUE(std::isfinite(sink));
}

// ---- Every detector's state: named values only ----

// A list longer than one value is a column of records (its siblings under the same prefix
// have its length) or a series of like values; never values told apart by their position.
TEST(DetectorStates, EveryValueHasAName) {
  const AvailableSignals all{true, true, true, true};
  for (const auto& kind : detector_kinds()) {
    auto detector = make_detector(kind, all, 0.04, nullptr);
    test::SyntheticRig rig;
    rig.onset = 120.0;
    rig.leak = 2e-12;
    rig.index_drop = 0.3;
    test::SyntheticPressures pressures;
    for (int i = 0; i < 4000; ++i) {
      Observation o = rig.next();
      const Observation samples = pressures.next();
      o.p1_samples = samples.p1_samples;
      o.p2_samples = samples.p2_samples;
      detector->update(o);
    }
    const DetectorState state = detector->export_state();
    std::map<std::string, std::set<std::size_t>> lengths;  // per prefix
    for (const auto& [key, values] : state.entries()) {
      const auto dot = key.rfind('.');
      lengths[dot == std::string::npos ? "" : key.substr(0, dot)].insert(values.size());
    }
    for (const auto& [key, values] : state.entries()) {
      if (values.size() <= 1) continue;
      const auto dot = key.rfind('.');
      const std::string prefix = dot == std::string::npos ? "" : key.substr(0, dot);
      const std::string name = key.substr(dot == std::string::npos ? 0 : dot + 1);
      const bool series = name == "history_a" || name == "history_b" || key == "learned";
      std::set<std::size_t> columns = lengths[prefix];
      columns.erase(0);
      columns.erase(1);
      const bool column = !prefix.empty() && columns.size() == 1;
      EXPECT_TRUE(series || column) << kind << ": " << key;
    }
  }
}

}  // namespace
}  // namespace leakmon::detect
