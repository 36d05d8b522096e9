// Flow balance in motion (issue #23): judges the valve's flow balance in every test program, not
// only at rest. Over each block of `block_seconds` the load flow the valve delivers by its
// orifice law (MODEL.md "Nominal model": the spool's first-order lag of sat(u / u_max), the
// rig's Kv, ps, pt, dp_lin) is integrated sample by sample (trapezoid, no differentiation of the
// noisy position) and regressed on what the piston must take:
//   Y = int qL dt ~ a A (x_end - x_start) + c int (p1 - p2) dt
//                   + k [(V1 p1) - (V2 p2)]_start^end / 2 + d T.
// a absorbs Kv's error (a = Kv_nominal / Kv_true), k ~ 1 / beta, c is the healthy cross-port
// term (the valve's null leakage) times a, d a constant flow offset. They are learned by least
// squares over the learning period; a single load (a hold alone) makes the cross-port term
// collinear with the offset, so learning waits for a spread of block loads
// (`min_load_spread`). Then a cross-piston leak C_L adds a C_L int (p1 - p2) dt to the residual:
// a block CUSUM tuned for `design_leak` tests it, with `min_leak` as the floor (as flow_balance).
// A block whose mean |p1 - p2| stays below `min_load` carries no information and is not judged.
// Laminar paths follow viscosity: with a `temp` observation the load term is scaled to 40 degC;
// without, the healthy slope is followed by the shared drift reference behind a guard.
// The spool's time constant is learned too (`learn_spool_time_constant`): valves on other rigs lag
// 1-20 ms (MODEL.md "Other rigs"), and a lag stated wrong moves the flow of every step's opening
// and closing into the neighbouring block, one block up and the next down, as the load swings
// with the step: the pattern of a leak. While learning, the flow is integrated for a ladder of
// time constants around the stated one; learning keeps the rung whose fit leaves the least, and a
// fifth regressor, the flow's slope between the neighbouring rungs, takes up the rest.
// A valve's null offset (MODEL.md `valve_bias`: the valve sees u + u0, the capture records u) adds
// the turbulent flow of a constant opening offset b, Kv b d qL / d o, which follows the pressures'
// square roots and not the oil's viscosity. Fitted by no other regressor, it was learned cold by
// the viscosity-scaled load term and the offset and over-predicted as the oil warmed (a morning
// start raised some 50 times; docs/detection.md). The sixth regressor is that flow per unit
// opening, d qL / d o at the block's openings integrated over the block; its coefficient is -b.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "detect/cusum.hpp"
#include "detect/detector.hpp"
#include "detect/drift_reference.hpp"
#include "detect/flow_law_ladder.hpp"
#include "detect/learned_change.hpp"
#include "detect/learning_schedule.hpp"
#include "detect/ring.hpp"
#include "detect/supply_tracker.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"

namespace leakmon::detect {

struct FlowLawOptions {
  // 90 s as flow_balance's and as `leakmon evaluate` measured it (docs/detection.md).
  LearningSchedule learning{2.0, 90.0};
  // The rig table: ps, pt, u_max, dp_lin, tau, Kv, the piston area A() and V0() are used.
  sim::Parameters rig;
  double block_seconds = 0.2;
  // Learning finishes only when the block-mean loads p1 - p2 of the learning blocks spread at
  // least this much (standard deviation) [Pa].
  double min_load_spread = 0.3e6;
  // ... and only when the learning blocks at rest lie at `min_rest_loads` loads p1 - p2 further
  // apart than `rest_load_tolerance` [Pa] (steps), or when at least kMotionBlockShare of them move
  // and the share of their load term's spread that the swept and compressed volumes and the
  // block length do not explain is at least `min_motion_load_share`. A fast sine's load term is
  // nearly a mix of the volumes (share 0.26; triangles 0.99): its model says little about the
  // load term elsewhere, but the learned range (max_leverage_ratio) keeps it from judging other
  // programs, so by default (0) moving blocks are enough and a rig running fast sines is judged
  // in them. 0 rest loads: the spread above alone (the build before issue 23's wait).
  double min_rest_loads = 3.0;
  double rest_load_tolerance = 0.3e6;
  double min_motion_load_share = 0.0;
  // A block with |mean p1 - p2| below this is not judged (no load, no leak flow) [Pa].
  double min_load = 0.3e6;
  // Scaled by the factory with Kv / 3.39e-7, as flow_balance's.
  double design_leak = 5e-13;
  double min_leak = 2.5e-13;
  double false_alarms_per_hour = 0.05;
  double sizing_seconds = 60.0;
  sim::Oil oil = sim::Oil::standard();
  double drift_guard_seconds = 30.0;
  double drift_window_seconds = 120.0;
  double rest_speed = 2e-3;  // [m/s] hops slower than this read the supply from the chambers ...
  double supply_rest_seconds = 0.2;  // ... once they have been for this long [s]
  // ... and when no rest has been read for this long, the mean of p1 + p2 - pt over that time
  // is a reading too: in motion the double-rod actuator's chambers take and give the same flow,
  // so the lands' pressure drops balance on average (a sine, sweep or triangle block never rests;
  // the paper's steps rest every few seconds). 0: rests only [s].
  double supply_motion_seconds = 5.0;
  bool estimate_supply = true;
  // Learn the spool's time constant from the learning blocks (a ladder of kTauCandidates values,
  // a third of an octave apart around rig.tau); false keeps rig.tau.
  bool learn_spool_time_constant = true;
  // ... but only when the learning blocks tell the lag from the load term: of the lag regressor's
  // spread that the other regressors leave unexplained, the load term must leave at least this
  // share (a slow sine: 0.04, where the lag follows the spring's load; steps 0.98, triangles
  // 0.75). Else the stated lag is kept.
  double min_lag_share = 0.25;
  // Fit the valve's null-offset flow (the sixth regressor); false: the model before it.
  bool learn_null_offset = true;
  // Fit the error of the stated tank pressure (the seventh regressor). The chambers' pressures
  // give ps + pt only (at rest and on average in motion), so an error in the stated pt moves
  // both lands' pressure drops by it, which bends the orifice law with the load's sign as a leak
  // does: a rig not described, its tank at 0.76 MPa against the table's 0.1, raised 22 times in
  // a 23-minute program (docs/detection.md). Kept only where the learning blocks tell it
  // (tank_offset_told, kMinTankShare, and a lag they told too); false: the model before it.
  bool learn_tank_pressure = true;
  // A block whose leverage on the learned fit (x' (X'X)^-1 x over the learning blocks' regressors)
  // exceeds this many times the largest learning block's is not judged: its flows lie beyond
  // those the coefficients were learned on (a fast sweep judged by a model learned on a slow
  // triangle extrapolates the spool lag's term); the status says `outside_learned_regime`.
  // 0: every block is judged (the build before).
  double max_leverage_ratio = 2.0;
  // Blocks outside the learned range are gathered; once this many seconds of them are, the model
  // is refitted on the learned blocks' normal equations and the new ones together, with the new
  // blocks' load term free of its own (a leak that opened with the new program, or the model's
  // bias there, would show in it). The range is extended to them when that term is told apart
  // from the others within `min_leak` and lies within it; else the oldest half is dropped and
  // the next ones gathered (docs/detection.md). 0: never extended (the build before).
  double range_extension_seconds = 30.0;
  // A leak that opened while learning, after a reference that identifies the model
  // (learned_change.hpp): learn on the blocks before it and judge those after it, so that it
  // raises internal_leakage. false: learn on every block and only report it (learned_change).
  bool learn_before_change = true;
  // A decision counts as judged while a block was judged within this time [s] (status, metrics).
  double judged_memory_seconds = 10.0;
};

class FlowLawDetector final : public Detector {
 public:
  FlowLawDetector(const FlowLawOptions& options, double hop_seconds);

  std::string_view name() const override { return "flow_law"; }
  Decision update(const Observation& observation) override;
  double raise_threshold() const override { return 1.0; }
  double clear_threshold() const override { return 0.5; }
  void reset() override;
  DetectorState export_state() const override;
  void import_state(const DetectorState& state) override;
  void resume_after_gap() override;
  // A leak that opened while learning and was learned as healthy (learned_change.hpp), found
  // once when learning ends; empty when learn_before_change left it out and judged it instead.
  std::optional<LearnedChange> learned_change() const override { return learned_change_; }
  double learning_seconds() const override {
    return options_.learning.settle_seconds + options_.learning.learn_seconds;
  }
  // The learning period is over but the blocks seen so far do not identify the model (a hold
  // alone, a hold and a few seconds of motion, a single sine): waiting for excitation.
  bool waiting_for_excitation() const { return waiting_; }
  static constexpr int kRegressors = 7;
  using Coefficients = Eigen::Matrix<double, kRegressors, 1>;
  // The learned coefficients [a, c, k, d, lag, null offset, tank offset] in normalised units
  // (a = Kv_nominal / Kv_true).
  Coefficients coefficients() const { return coefficients_; }
  std::size_t blocks_not_judged_no_load() const { return no_load_blocks_; }
  std::size_t blocks_not_judged_outside_learned_range() const { return outside_range_blocks_; }
  // The largest leverage among the learning blocks (NaN before learning, or from a layout-5
  // state, which judges every block as its build did).
  double max_learned_leverage() const { return max_learned_leverage_; }
  // How often the learned range was extended to a new program since construction, reset or
  // restore, and what the latest attempt found: the new blocks' own load slope and its standard
  // error in m^3/(s Pa) (NaN before any attempt; diagnostics and tests, not saved).
  struct RangeExtension {
    std::size_t attempts = 0, extensions = 0;
    double added_leak = kMissing, added_leak_error = kMissing;
  };
  RangeExtension range_extension() const { return range_extension_; }
  // How often motion resuming after a wait at rest started the learning period over since
  // construction, reset or restore (diagnostics and tests; not saved).
  std::size_t learning_restarts() const { return learning_restarts_; }
  // The supply the flows are integrated with now [Pa] (the stated one before any reading).
  double supply() const { return supply_tracker_.estimate(); }
  // How often a leak that opened while learning was left out of the learning and judged
  // (learn_before_change) since construction, reset or restore (diagnostics; not saved).
  std::size_t changes_judged_after_learning() const { return changes_judged_after_learning_; }
  // The spool time constant the flow is integrated with: learned (or rig.tau when not learned
  // from the data); NaN while learning still weighs the ladder.
  double spool_time_constant() const;

  // Layout 2 adds the time-constant ladder (layout 1 loads with the stated time constant kept);
  // layout 3 the hops at rest before the supply is read and the CUSUM's run for the change point
  // (layout 2 loads as long at rest and with an empty run).
  // Layout 4 marks the learning blocks at rest and the block in progress's fastest hop (layout 3's
  // blocks load as moving, its block in progress as moving).
  // Layout 5 adds the null-offset regressor (layout 4's learning blocks load without it, and
  // learning then fits without it as the build that wrote them would; its coefficient is 0).
  // Layout 6 adds the learned range: (X'X)^-1 and the largest learning leverage (layout 5 loads
  // without them and judges every block, as its build did). Layout 7 reads the supply in motion
  // too (`supply_motion.*`; layout 6 loads reading it at rest only, as its build did).
  // Layout 8 adds the tank-offset regressor (layout 7 loads as layout 4 did the null offset).
  static constexpr int kStateVersion = 8;
  // Motion alone identifies the load term only when at least this share of the learning blocks
  // move: a long hold with a few seconds of a sweep has a sharp but biased load term.
  static constexpr double kMotionBlockShare = 0.75;
  // A rest load counts once this many blocks at rest lie at it (a second): the first steps after
  // a long other program do not end learning on a window that is mostly that program.
  static constexpr std::size_t kRestLoadBlocks = 5;
  // Motion resuming after a wait whose window moved in under this share of its blocks starts the
  // learning period over (restart_learning_on_motion), keeping the hold's newest seconds.
  static constexpr double kHoldMotionShare = 0.25;
  static constexpr double kHoldSecondsKept = 5.0;
  // The tank offset is kept where its coefficient exceeds this many standard errors and the tank
  // pressure it implies lies within 0 .. kMaxTankPressure [Pa] (tank_offset_told).
  static constexpr double kTankOffsetStandardErrors = 5.0;
  static constexpr double kMaxTankPressure = 2e6;
  // ... and only when the learning blocks tell it from the load term (as min_lag_share for the
  // lag): of its regressor's spread that the other terms leave, the load term must leave at least
  // this share (tank_load_share).
  static constexpr double kMinTankShare = 0.25;
  // What the latest check of the learning blocks found since construction, reset or restore
  // (diagnostics and tests; not saved): the distinct loads at rest and the motion's share of the
  // load term (NaN: under kMotionBlockShare moving, or too few).
  struct Excitation {
    std::size_t rest_loads = 0;
    std::size_t moving_blocks = 0, blocks = 0;
    double motion_load_share = kMissing;
  };
  Excitation excitation() const { return excitation_; }
  // The ladder (flow_law_ladder.hpp).
  static constexpr std::size_t kTauCandidates = detect::kTauCandidates;
  static constexpr std::size_t kStatedTau = detect::kStatedTau;
  static constexpr std::size_t kTauNotChosen = kTauCandidates;

 private:
  // One closed block, regressors in units of the valve's full flow Kv sqrt(ps) times seconds.
  struct Block {
    double t = kMissing;
    double y = kMissing;          // int qL dt with the chosen time constant
    double move = kMissing;       // A dx
    double load = kMissing;       // int (p1 - p2) dt / ps (times the viscosity ratio with temp)
    double comp = kMissing;       // compressibility term / beta_nominal
    double length = kMissing;     // T
    double mean_load = kMissing;  // mean p1 - p2 [Pa]
    double lag = kMissing;        // d int qL dt per rung of the time-constant ladder
    double moving = 1.0;          // 0: every hop of the block slower than rest_speed
    double null_offset = 0.0;     // int d qL / d o dt, the flow per unit opening offset
    double tank_offset = 0.0;     // int d qL / d (dp / ps) dt, both lands' drops moved by dp
    std::array<double, kTauCandidates> y_tau{};  // int qL dt per rung (read while learning)
  };
  static constexpr std::array<RecordField<Block>, 11> block_fields() {
    return {record_field<&Block::t>("t"),
            record_field<&Block::y>("y"),
            record_field<&Block::move>("move"),
            record_field<&Block::load>("load"),
            record_field<&Block::comp>("comp"),
            record_field<&Block::length>("length"),
            record_field<&Block::mean_load>("mean_load"),
            record_field<&Block::lag>("lag"),
            record_field<&Block::moving>("moving"),
            record_field<&Block::null_offset>("null_offset"),
            record_field<&Block::tank_offset>("tank_offset")};
  }
  static Coefficients regressors(const Block& b) {
    Coefficients r;
    r << b.move, b.load, b.comp, b.length, b.lag, b.null_offset, b.tank_offset;
    return r;
  }
  // The regressors as the model was fitted on them: a regressor left out of the fit was a zero
  // column while learning (its coefficient 0), so the range has no extent along it.
  Coefficients fitted_regressors(const Block& b) const {
    Coefficients r = regressors(b);
    if (!fit_null_offset_) r[5] = 0.0;
    if (!fit_tank_offset_) r[6] = 0.0;
    return r;
  }
  double residual(const Block& b) const { return b.y - coefficients_.dot(regressors(b)); }

  // The rungs of the ladder integrated, first to last.
  struct Rungs {
    std::size_t first, last;
  };
  Rungs active_rungs() const;
  void reset_spool_time_constant();
  void set_chosen_flow(Block& b) const;
  void choose_spool_time_constant();
  static double lag_load_share(std::span<const Block> blocks);
  static double tank_load_share(std::span<const Block> blocks);
  bool tank_offset_told(std::span<const Block> blocks) const;
  void drop_tank_offset();
  void restart_block();
  void add_sample(double u, double x, double p1, double p2);
  void close_block(double t, bool past_settling);
  void learn(const Block& b);
  bool excited(std::span<const Block> blocks) const;
  // Whether the learning blocks identify the model (excited, and the rest loads or the motion of
  // min_rest_loads); sets excitation_. Uses rest_loads_.
  bool identified();
  bool resumes_after_hold() const;
  void restart_learning_on_motion();
  double motion_load_share(std::span<const Block> blocks) const;
  void probe_learned_change();
  void finish_learning();
  void fit_healthy(std::span<const Block> blocks);
  void judge(const Block& b);
  Decision decide() const;

  FlowLawOptions options_;
  double hop_seconds_;
  std::size_t block_hops_;
  double flow_unit_;     // Kv sqrt(ps) [m^3/s]
  double design_slope_;  // design_leak in the load regressor's units (before a)
  double floor_slope_;
  double sizing_decay_;
  std::size_t rest_hops_;    // supply_rest_seconds in hops
  std::size_t motion_hops_;  // supply_motion_seconds in hops (0: off)
  LearningClock clock_;
  std::vector<Block> learned_;  // reserved at construction; the newest when waiting
  std::size_t learn_capacity_;
  Coefficients coefficients_ = Coefficients::Zero();
  double block_sigma_ = kMissing;
  // The learned range: (X'X)^-1 of the learning blocks and their largest leverage (NaN: unknown).
  Eigen::Matrix<double, kRegressors, kRegressors> inverse_normal_ =
      Eigen::Matrix<double, kRegressors, kRegressors>::Zero();
  double max_learned_leverage_ = kMissing;
  std::size_t outside_range_blocks_ = 0;
  bool outside_learned_range(const Block& b) const;
  // The blocks outside the range gathered for its extension (reserved at construction).
  std::vector<Block> outside_;
  std::size_t extension_blocks_ = 0;  // range_extension_seconds in blocks (0: off)
  RangeExtension range_extension_;
  void extend_learned_range();
  bool waiting_ = false;
  std::size_t learning_restarts_ = 0;
  std::size_t changes_judged_after_learning_ = 0;
  Excitation excitation_;
  std::vector<double> rest_loads_;  // scratch, reserved as learned_
  std::size_t no_load_blocks_ = 0;
  // What the status says: when a block was last judged, and why the latest one was not.
  double last_judged_t_ = kMissing;
  double last_t_ = kMissing;
  NotJudgedReason block_reason_ = NotJudgedReason::learning;
  // Per hop.
  double supply_ = kMissing;  // supply used this hop [Pa]
  double viscosity_ratio_ = kMissing;
  bool hop_usable_ = false;
  double sample_seconds_ = kMissing;
  double previous_x_ = kMissing;  // hop mean, for the rest test of the supply estimate
  std::size_t still_hops_ = 0;    // consecutive hops at rest, for the same
  // The supply read in motion: p1 + p2 - pt summed over the hops since the last reading, and
  // whether this state reads it (a state of layout 6 or before does not, as its build did not).
  double motion_supply_sum_ = 0.0;
  std::size_t motion_supply_hops_ = 0;
  bool reads_supply_in_motion_ = true;
  // A first reading of the supply that differs from the stated one by a step: the learning
  // blocks so far were integrated with the wrong supply and are dropped.
  void restart_learning_on_first_supply(double reading);
  // The time-constant ladder: kTauNotChosen while every candidate is integrated.
  std::array<double, kTauCandidates> taus_{};
  std::size_t tau_index_ = kTauNotChosen;
  bool fit_lag_ = true;  // false: the chosen rung's flow alone (not learned, or an old layout)
  // false: learning blocks from a layout without the null-offset regressor are among those
  // learned on; the fit leaves it out (coefficient 0) until the next reset.
  bool fit_null_offset_ = true;
  bool fit_tank_offset_ = true;
  // Per sample and candidate: the spool (exact zero-order-hold lag) and the previous flow.
  std::array<double, kTauCandidates> openings_{};
  std::array<double, kTauCandidates> previous_flows_{};
  double previous_command_ = kMissing;
  bool have_previous_ = false;
  double previous_load_ = 0.0;
  double last_x_ = 0.0, last_p1_ = 0.0, last_p2_ = 0.0;
  // The current block.
  std::size_t block_hop_ = 0;
  bool block_ok_ = false;
  double start_x_ = 0.0, start_p1_ = 0.0, start_p2_ = 0.0;
  std::array<double, kTauCandidates> sum_flows_{};
  double previous_gain_ = 0.0, sum_gain_ = 0.0;  // d qL / d o per sample, and its integral
  double previous_tank_gain_ = 0.0, sum_tank_gain_ = 0.0;  // d qL / d (dp / ps), and its integral
  double sum_load_ = 0.0, block_length_ = 0.0, ratio_sum_ = 0.0;
  std::size_t ratio_hops_ = 0;
  double block_max_speed_ = 0.0;  // the block's fastest hop [m/s] (NaN: unknown, moving)
  // The added slope on the load term: exponentially weighted, and from the change point on.
  struct SlopeSums {
    double rl = 0.0, ll = 0.0;
  };
  SlopeSums weighted_, since_change_;
  // The judged blocks of the CUSUM's current run (since it left zero), the newest
  // `sizing_seconds` of them: the change point is the block within it from which on the added
  // slope explains the most (since_change_ holds the sums from there).
  static constexpr std::array<RecordField<SlopeSums>, 2> run_fields() {
    return {record_field<&SlopeSums::rl>("rl"), record_field<&SlopeSums::ll>("ll")};
  }
  void estimate_change_point();
  Ring<SlopeSums> run_;
  BlockCusum cusum_;
  SupplyTracker supply_tracker_;
  bool temperature_seen_ = false;
  DriftReference drift_;
  Decision last_;
  // The learned-change probe's blocks (reserved as learned_) and its finding.
  std::vector<ResidualBlock> probe_blocks_;
  std::optional<LearnedChange> learned_change_;
};

}  // namespace leakmon::detect
