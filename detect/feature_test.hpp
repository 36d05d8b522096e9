// The sequential test of one pressure feature (a per-hop number that a leak lowers: the log of
// the wavelet index, the detail correlation) against its healthy model. A healthy feature
// still moves with the operating point, so the test learns, per rig, a quadratic model of it
// in the load pressure plus the log of the load's activity, and tests the residual: blocks of
// `block_seconds` (nearly independent), a CUSUM for a shift of FeaturePhysics::design_shift
// against the null null_shift, its threshold from the target false-alarm rate and, once the
// block spread is learned, the designed shift in spreads (Siegmund's approximation).
//
// A real rig drifts (MODEL.md "Drifting operating conditions") and so does the healthy feature:
// - With a `temp` observation (when the physics uses it) the log of the viscous friction
//   factor is a regressor; its coefficient is learned, pulled towards a prior as far as the
//   learning period saw too little temperature range to identify it.
// - The supply is read from a `ps` observation or, with both chambers, from p1 + p2 = ps + pt at
//   rest (SupplyTracker, rule drift_from_anchor); the load is normalised by it and the feature
//   shifted by supply_exponent ln(ps). After a step of the supply the test does not judge for
//   a while and re-anchors its drift reference on the blocks after the step.
// - With one chamber and no `ps` the supply is read from that chamber's hold levels
//   (ChamberSupplyTracker). A hold that fits neither of its clusters is a supply step: the
//   blocks judged since the step began are taken back out of the CUSUM, and the test does not
//   judge until the holds after the step give the new supply, then re-anchors as above.
// - What is left of slow drift is followed (DriftReference): blocks are judged against a trend
//   of the residuals in a window that ends `drift_guard_seconds` ago, or at the last block when
//   the blocks stopped (another program, a suspicious stretch): held, not slid past them.
// Test programs (MODEL.md "Test programs", issue 23) change the excitation by orders of
// magnitude, and with it every feature the pressures give:
// - Learning waits for a program that moves and rests (steps, which ring the mode): a learning
//   period whose blocks' log load activity spans less than `min_excitation_range` (a hold, a
//   steady sine) is discarded and learning starts over (`waiting_for_excitation`), for at most
//   `max_excitation_wait_seconds`, then `cannot_learn`. A baseline learned on an unexcited hold
//   reads the first steps as a leak (its load and activity regressors were constants).
// - The program is told by how much it rests: the share of hops at rest over kRegimeBlocks
//   blocks (steps move and rest, a sine, sweep or triangle hardly rests, a hold only rests; a
//   leak changes none of it). Its range over the learning period is the regime learned; where
//   the share lies further outside it than `regime_tolerance`, the program is one the learning
//   did not see (`outside_learned_regime`): its blocks go neither into the CUSUM nor into the
//   drift reference, and the blocks since the excursion began are taken back out of both. The
//   feature's model (learned on steps) does not hold there: a 0.5 Hz sine rings the mode less,
//   which read as a leak.
// - The share over kRegimeBlocks blocks is slow to see a program change (and blind to a hold
//   after steps, which rest most of the time too), so the runs of hops at rest and in motion
//   are read as well: steps hold a level for at most a few seconds and move for a fraction of
//   one. A block whose rest run or motion run exceeds kRunFactor times the longest the
//   learning period saw (plus kMotionRunSlackSeconds for a motion) is outside the learned
//   regime: a hold after about twice the steps' longest level, a sine within a second or two.
// - For the same reason a learning period must be one such program: every kRegimeBlocks
//   window rests for at least kLearningRestShare of its hops and no rest run is longer than
//   kLongestLearningRestSeconds. A period that breaks either is discarded at the block that
//   shows it (not at its end), so the next period begins with the program that follows. A
//   period learned across a program change took both programs' rest shares as its regime and
//   judged either by one model. min_excitation_range 0 switches these checks off as well.
// - Another program that lasts a learning period and rings the mode (a sine, triangle or sweep
//   block of minutes; not a hold, whose rest run outlasts any level of steps) is learned as a
//   regime of its own, up to kMaxOtherRegimes: its rest share, mean log load activity and
//   longest runs say when it runs again, and its own baseline of the feature (the constant,
//   with the load and activity terms pulled towards the steps' as far as the block saw too
//   little of them) judges it then, in spreads of its own. What a leak does to the feature is
//   the same in every program; what the excitation changes is the baseline. A period that
//   changes program (its rest share or activity moves by more than a program's own scatter)
//   starts over. A program neither learned nor learnable stays `outside_learned_regime`.
//   Such a program is learned and judged before the steps are learned too (a shift that
//   begins with a durability block), while the steps' learning waits beside it.
// - Rest share and activity do not see frequency: a sweep passing a learned sine's activity
//   (about amplitude x frequency) was told as that sine and judged by its baseline at twice its
//   frequency. So a program is also told by its reversal rate, the load's changes of direction
//   per second over kRegimeBlocks blocks (a sine's is twice its frequency); a learned program
//   stays told only while the rate lies within kFrequencyTolerance (in ln) of its learned range,
//   and a learning period whose rate moves by more than twice that began in another program.
// The detectors on top (index_cusum, detail_xcorr) say what the feature is and how it moves:
// that is all they add.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "detect/chamber_supply_tracker.hpp"
#include "detect/cusum.hpp"
#include "detect/detector.hpp"
#include "detect/drift_reference.hpp"
#include "detect/learning_schedule.hpp"
#include "detect/ring.hpp"
#include "detect/supply_tracker.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"

namespace leakmon::detect {

// The rig and the timing: what every detector on this test is configured with.
struct FeatureTestOptions {
  LearningSchedule learning;
  bool use_p1 = true, use_p2 = true;  // the chambers acquired (the load and supply come from them)
  sim::Parameters rig;  // ps: the configured supply (used until one is measured); pt: tank
  double false_alarms_per_hour = 0.05;  // sets the threshold
  double block_seconds = 0.8;           // one window (400 samples at 500 Hz)
  // Drift following (see the file comment); 0 window switches it off.
  double drift_guard_seconds = 60.0;
  double drift_window_seconds = 240.0;
  // After a supply step: no judging for this long while the reference re-anchors.
  double supply_settle_seconds = 20.0;
  // Learning waits for excitation (see the file comment): the spread (10 % to 90 % quantile)
  // of the learning period's block log load activity it needs; 0 learns from any period.
  double min_excitation_range = 1.0;
  double max_excitation_wait_seconds = 1800.0;
  // Judging only in the learned regime: how far (as a share of hops) the rest share of the last
  // kRegimeBlocks blocks may lie outside the learned range; 0 judges in any regime.
  double regime_tolerance = 0.15;
};

// What the feature is: how a leak, the supply and the oil move it.
struct FeaturePhysics {
  // The shift of a block's mean feature the CUSUM is tuned for, and the shift that is never an
  // alarm (the null), in the feature's units; a leak lowers the feature, so both are negative.
  // |design_shift| also bounds the drift reference's extrapolation.
  double design_shift = -0.08;
  double null_shift = -0.02;
  // d feature / d ln(ps): known physics, not learned (learning rarely sees two supplies).
  double supply_exponent = 0.0;
  // Whether a `temp` observation is used. Its regressor is -ln(friction factor 0.5 + 0.5 / r)
  // with r = nu(40) / nu(T) of `oil`; `temperature_prior` is the coefficient assumed as far as
  // learning saw too little temperature range, `temperature_prior_sigma` its uncertainty.
  bool uses_temperature = false;
  // Whether the CUSUM's threshold follows the learned spread (Siegmund's approximation at the
  // designed shift in spreads) instead of Lorden's bound. detail_xcorr (issue 23); the log index
  // keeps Lorden's: with Siegmund's it raised on the simulated rig's warm-up without `temp`
  // (index_drift_sim_test), a drift its feature follows less well than the correlation.
  bool threshold_from_spread = false;
  double temperature_prior = 0.0;
  double temperature_prior_sigma = 0.05;
  sim::Oil oil = sim::Oil::standard();
};

class FeatureTest {
 public:
  FeatureTest(const FeatureTestOptions& options, const FeaturePhysics& physics, double hop_seconds);

  struct Verdict {
    bool learning = true;
    double learning_hops_left = kMissing;  // while learning
    double score = kMissing;               // CUSUM / threshold; NaN when it cannot judge
    // The healthy feature (drift reference included) the latest judged block was held against.
    double expected = kMissing;
    // Why the test does not judge (none while it does, and while it is merely learning).
    NotJudgedReason not_judged = NotJudgedReason::none;
    // After Decision::judge_by_score(): the test's reason, where it has one, overrides.
    void apply_to(Decision& decision) const {
      if (not_judged == NotJudgedReason::none) return;
      decision.judged = false;
      decision.not_judged_reason = not_judged;
    }
  };
  // Blocks whose rest shares are averaged for the regime test.
  static constexpr std::size_t kRegimeBlocks = 8;
  // The run test (see the file comment): how much longer than the learning period's longest
  // rest or motion run a run may last in the learned regime, and the motion's slack (steps
  // move for 0.3-0.5 s; a run a hop or two longer is still a step).
  static constexpr double kRunFactor = 2.0;
  static constexpr double kMotionRunSlackSeconds = 0.2;
  // What a learning period must show to be one program that moves and rests (the file comment).
  static constexpr double kLearningRestShare = 0.3;
  static constexpr double kLongestLearningRestSeconds = 20.0;
  // Per-regime learning (the file comment): how many programs besides the first one are
  // learned, and how far (in ln) a program's mean log load activity over kRegimeBlocks blocks
  // may lie outside its learned range and still be that program (a sine at another amplitude or
  // frequency moves the load's activity by its ratio). 0.2: a 2.85 Hz, 40 mm sine lay 0.23 from
  // a learned 2.74 Hz, 32 mm one and 4 % from its rate, was judged by its baseline at 0.4 and
  // raised a false leak (docs/detection.md, 2026-11-30, seed 5150 run 24). The same tolerance
  // bounds a learning period: one whose mean activity spans more than twice it starts over.
  static constexpr std::size_t kMaxOtherRegimes = 3;
  static constexpr double kActivityTolerance = 0.2;
  // How far (in ln) a program's reversal rate over kRegimeBlocks blocks may lie outside its
  // learned range and still be that program (a sine within about 20 % of its frequency), and the
  // rate below which reversals are compared as this (a 0.1 Hz sine: the ln stays finite).
  static constexpr double kFrequencyTolerance = 0.2;
  static constexpr double kReversalFloor = 0.2;
  // The other regime whose baseline judges the current blocks (-1: none), and how many are
  // learned: for the tests and the status.
  int judging_regime() const { return judging_other_; }
  std::size_t other_regimes() const { return other_count_; }
  // One hop: `feature` over the window that ended at o.t (NaN: a gap; nothing is judged then),
  // with the observation's pressures (and its temperature when the physics uses it).
  Verdict update(const Observation& o, double feature);

  static constexpr double raise_threshold() { return 1.0; }
  // The CUSUM's threshold [nats]: Lorden's until the block spread is learned, then Siegmund's.
  double cusum_threshold() const { return cusum_.threshold(); }
  static constexpr double clear_threshold() { return 0.5; }
  double learning_seconds() const {
    return options_.learning.settle_seconds + options_.learning.learn_seconds;
  }
  void reset();
  // The drift reference, the supply transient and the CUSUM's take-back history are on the
  // old source clock; the hop before the gap is not a neighbour of the next one.
  void resume_after_gap();

  void save(DetectorState& state, std::string_view prefix) const;
  void restore(const DetectorState& state, std::string_view prefix);

 private:
  // One block's means: the response and its regressors.
  struct Block {
    double t, feature, load, load_squared, log_activity, log_friction, log_supply, rest_share;
    double reversal_rate;  // the load's changes of direction per second (NaN: a state before)
  };
  static constexpr std::array<RecordField<Block>, 9> kBlockFields = {
      record_field<&Block::t>("t"),
      record_field<&Block::feature>("feature"),
      record_field<&Block::load>("load"),
      record_field<&Block::load_squared>("load_squared"),
      record_field<&Block::log_activity>("log_activity"),
      record_field<&Block::log_friction>("log_friction"),
      record_field<&Block::log_supply>("log_supply"),
      record_field<&Block::rest_share>("rest_share"),
      record_field<&Block::reversal_rate>("reversal_rate")};
  struct WindowRange {
    double low, high;
  };
  static WindowRange window_mean_range(std::span<const Block> blocks, double Block::*field);
  // The range of the blocks' reversal rate; NaN where no window has one (blocks of a state
  // from before it).
  static WindowRange reversal_range(std::span<const Block> blocks);
  // A block of the regime test: its share of hops at rest, and its feature residual
  // waiting to enter the drift reference (NaN: it does not) until kRegimeBlocks later blocks
  // showed no excursion.
  struct RegimeEntry {
    double t, share, residual, activity, reversals;
  };
  static constexpr std::array<RecordField<RegimeEntry>, 5> kRegimeFields = {
      record_field<&RegimeEntry::t>("t"), record_field<&RegimeEntry::share>("share"),
      record_field<&RegimeEntry::residual>("residual"),
      record_field<&RegimeEntry::activity>("activity"),
      record_field<&RegimeEntry::reversals>("reversals")};
  // A program learned besides the first: the feature's model in it (constant, load, load^2,
  // log activity; the temperature term is the first program's), its block spread, the drift
  // reference when it was learned (its baseline moves with the reference since), and what tells
  // it: the range of its rest share and mean log activity over kRegimeBlocks blocks, and its
  // longest rest and motion runs [s], and the range of its reversal rate [1/s] (NaN: learned by
  // a build that did not read it).
  struct OtherRegime {
    double constant, load, load_squared, log_activity, sigma, reference;
    double rest_low, rest_high, activity_low, activity_high, longest_rest, longest_motion;
    double reversals_low, reversals_high;
  };
  static constexpr std::array<RecordField<OtherRegime>, 14> kOtherRegimeFields = {
      record_field<&OtherRegime::constant>("constant"),
      record_field<&OtherRegime::load>("load"),
      record_field<&OtherRegime::load_squared>("load_squared"),
      record_field<&OtherRegime::log_activity>("log_activity"),
      record_field<&OtherRegime::sigma>("sigma"),
      record_field<&OtherRegime::reference>("reference"),
      record_field<&OtherRegime::rest_low>("rest_low"),
      record_field<&OtherRegime::rest_high>("rest_high"),
      record_field<&OtherRegime::activity_low>("activity_low"),
      record_field<&OtherRegime::activity_high>("activity_high"),
      record_field<&OtherRegime::longest_rest>("longest_rest"),
      record_field<&OtherRegime::longest_motion>("longest_motion"),
      record_field<&OtherRegime::reversals_low>("reversals_low"),
      record_field<&OtherRegime::reversals_high>("reversals_high")};
  static constexpr int kRegressors = 5;
  double load_of(const Observation& o, double supply) const;
  double expected_feature(const Block& block) const;
  bool add_to_block(const Observation& o, double temp, double feature, double load, double supply,
                    Block& completed);
  // At the end of a learning period: whether its blocks show the mode ringing.
  bool excited_enough();
  // While learning, after each block: no hold and no window that hardly rests so far.
  bool one_program_so_far() const;
  // Whether the block lies outside the learned regime (it joins the regime ring).
  bool outside_regime(const Block& block);
  // Whether the block's longest rest or motion run exceeds what the learning period saw.
  bool runs_outside() const;
  // The rest and motion runs: one hop whose load activity is known.
  void count_run(bool at_rest);
  double hop_seconds() const { return options_.block_seconds / static_cast<double>(block_hops_); }
  void add_to_reference(const Block& block, double residual);
  bool regime_known() const { return !std::isnan(learned_rest_low_); }
  bool runs_known() const { return !std::isnan(learned_longest_rest_); }
  // Outside the first program: the learned other program the ring's blocks show (-1: none).
  int other_regime_of_ring() const;
  // An unrecognised program's block: learning it as another regime, or starting over.
  void learn_other(const Block& block);
  void finish_other();
  // Leaving the regime whose baseline judged the ring's blocks: they belong to the next program.
  void take_back_ring();
  double other_expected(const OtherRegime& r, const Block& block) const;
  void judge_other(const Block& block, std::size_t other, double reference);
  // Before the steps are learned: a program without rests learned and judged as another regime
  // (the file comment); true when the hop is judged so.
  bool judge_without_steps(bool completed, const Block& block, Verdict& verdict);
  double supply_for(const Observation& o, double load);
  double supply_from_chamber(const Observation& o, double load);
  void finish_learning();
  void set_threshold_for_sigma();
  double anchored_until() const;

  FeatureTestOptions options_;
  FeaturePhysics physics_;
  std::size_t block_hops_;
  LearningClock clock_;
  std::vector<Block> learned_;  // reserved at construction
  double coefficients_[kRegressors] = {0.0, 0.0, 0.0, 0.0, 0.0};
  double block_sigma_ = kMissing;  // long-run std. dev. of a block's residual
  // The learned range of the rest share; NaN when not learned (a state from before issue 23:
  // then every block is judged).
  double learned_rest_low_ = kMissing, learned_rest_high_ = kMissing;
  bool outside_ = false;
  // The longest rest and motion runs [s] of the learning period; NaN when not learned (a state
  // from before the run test: then only the rest share tells the regime).
  double learned_longest_rest_ = kMissing, learned_longest_motion_ = kMissing;
  // The current runs of hops at rest and in motion, the longest of each that ended in (or
  // reached into) the block being filled, that of the last completed block, and the longest over
  // the learning period so far (all in hops).
  std::size_t rest_run_ = 0, motion_run_ = 0;
  std::size_t block_rest_run_ = 0, block_motion_run_ = 0;
  std::size_t completed_rest_run_ = 0, completed_motion_run_ = 0;
  std::size_t learning_rest_run_ = 0, learning_motion_run_ = 0;
  double excitation_wait_seconds_ = 0.0;  // learning periods discarded for want of excitation
  bool cannot_learn_ = false;
  // Whether learning waits for excitation; off for a state from a build before it.
  bool waits_for_excitation_ = true;
  // Whether the threshold follows the learned spread (Siegmund's); off for a state from a build
  // before it, which then decides as that build did (Lorden's).
  bool siegmund_threshold_ = true;
  std::vector<double> scratch_;  // quantiles at the end of learning; reserved at construction
  // The block being filled.
  std::size_t block_hop_ = 0, block_valid_ = 0;
  double sum_feature_ = 0.0, sum_load_ = 0.0, sum_load_squared_ = 0.0, sum_activity_ = 0.0;
  double sum_log_friction_ = 0.0, sum_log_supply_ = 0.0;
  std::size_t rest_hops_ = 0;  // the block's valid hops at rest
  // The direction of the load's last move (+1, -1; 0 none yet), and the block's reversals of it.
  double last_direction_ = 0.0;
  std::size_t reversals_ = 0;
  double previous_load_ = kMissing;
  double previous_rough_load_ = kMissing;  // normalised by the configured supply
  double last_expected_ = kMissing;
  bool temperature_seen_ = false;
  bool one_chamber_;  // p1 or p2 alone: without `ps` the supply comes from its hold levels
  SupplyTracker supply_;
  ChamberSupplyTracker chamber_supply_;
  double learned_supply_ = kMissing;  // the supply the learning period's blocks were formed with
  BlockCusum cusum_;
  DriftReference drift_;
  Ring<RegimeEntry> regime_;  // the latest kRegimeBlocks judged or excluded blocks
  std::array<OtherRegime, kMaxOtherRegimes> others_{};
  std::size_t other_count_ = 0;
  int judging_other_ = -1;
  // Whether other programs are learned; off for a state from a build before it (judges as then).
  bool learns_other_regimes_ = true;
  // The blocks of an unrecognised program so far, and their longest runs [hops].
  std::vector<Block> candidate_;  // reserved at construction
  std::size_t candidate_rest_run_ = 0, candidate_motion_run_ = 0;
};

}  // namespace leakmon::detect
