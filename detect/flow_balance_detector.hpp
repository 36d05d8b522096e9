// Model-aware leak detector for configurations that acquire the command u and position x as
// well as both chamber pressures. At rest the valve must deliver what leaks across the piston:
// Kv * o * R(p1, p2) = C_L (p1 - p2) + (null leakage), with o the spool opening and R the
// orifice law's root factor (valve_flow.hpp) on the side the load makes the valve open to. So
// the command at rest is u / u_max = offset + C (p1 - p2) / (Kv R): the test works in command
// units. During learning the healthy at-rest command is fitted against the load (healthy_terms:
// null leakage, valve bias, spool overlap and the curvature that spool noise around the overlap
// edge gives it); afterwards the residual of blocks at rest is tested for an added slope
// C_L / Kv on (p1 - p2) / R with a CUSUM tuned for `design_leak`. The slope is what is
// identifiable: C_L = Kv times the slope change, with Kv known only to
// +-`valve_coefficient_uncertainty`, which the reported confidence interval includes. The
// controller's integral action or position error does not matter: whatever hides the leak from
// x, the valve still has to be opened to feed it.
//
// A real rig drifts (MODEL.md "Drifting operating conditions"). Every laminar leak path, the
// valve's null leakage included, follows the oil's viscosity: at rest a warmer oil looks exactly
// like a cross-piston leak. With a `temp` observation the leak term is scaled to 40 degC by the
// viscosity ratio, so the learned null leakage and the reported leak size are both stated at the
// reference temperature. Without one, the healthy slope is followed as a trend fitted to the
// blocks of a reference window that ends `drift_guard_seconds` ago: a leak opens within a
// second or so and is judged long before it reaches that window, while the oil's drift (at most
// a few 1e-15 m^3/(s Pa) per second) is tracked. The supply pressure is read from a `ps`
// observation or, without one, from the chamber pressures at rest (p1 + p2 = ps + pt there).
// A leak smaller than `min_leak` (at 40 degC) is never an alarm, however significant.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "detect/cusum.hpp"
#include "detect/detector.hpp"
#include "detect/drift_reference.hpp"
#include "detect/learned_change.hpp"
#include "detect/learning_schedule.hpp"
#include "detect/supply_tracker.hpp"
#include "detect/valve_flow.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"

namespace leakmon::detect {

struct FlowBalanceOptions {
  LearningSchedule learning;
  // The rig table: ps, pt, u_max, dp_lin, the nominal Kv and the piston area A() are used
  // (options supply_pressure, tank_pressure, command_full_scale, valve_coefficient,
  // piston_area).
  sim::Parameters rig;
  double valve_coefficient_uncertainty = 0.1;  // relative
  // A hop is at rest when |dx/dt| stays below rest_speed over it and both its neighbours: a hop
  // that holds the first or last few samples of a move carries flows the balance does not model.
  double rest_speed = 2e-3;  // [m/s]
  // C_L the CUSUM is tuned for [m^3/(s Pa)]; the factory scales this default and min_leak's by
  // the valve's Kv over the paper's 3.39e-7 (a leak of interest is a share of the valve's flow).
  double design_leak = 2.5e-13;
  double false_alarms_per_hour = 0.05;
  double block_seconds = 0.8;
  double min_rest_fraction = 0.25;  // a block needs this share of hops at rest
  double sizing_seconds = 60.0;     // memory of the C_L estimate when there is no change
  // Oil grade: the viscosity ratio that scales laminar leaks with a `temp` observation.
  sim::Oil oil = sim::Oil::standard();
  // Minimum leak of interest at 40 degC [m^3/(s Pa)]: the CUSUM drifts down below it, so a
  // significant but practically irrelevant change (or what is left of the oil's drift) does
  // not raise. 5e-13 is 0.03 l/min/MPa, a seventh of the paper's smallest leak.
  double min_leak = 5e-13;
  // Drift following without a `temp` observation (see the class comment).
  double drift_guard_seconds = 30.0;
  double drift_window_seconds = 120.0;
  // Supply from the chamber pressures at rest when there is no `ps` observation.
  bool estimate_supply = true;
  // Excitation (MODEL.md "Test programs"). The healthy command is fitted against the load on
  // each side of zero load, so learning needs `min_rest_loads` rests, counted on the sides whose
  // rests lie at loads p1 - p2 further apart than `rest_load_tolerance` [Pa] (a side without is
  // left out and not judged; one with fewer than three rests has no curvature term): a hold
  // gives one load, from which the fit extrapolates wildly.
  // A learning period without them starts over, for at most `max_excitation_wait_seconds`
  // after the first; then the detector says it cannot learn rather than learn a wrong model.
  double min_rest_loads = 3.0;
  double rest_load_tolerance = 0.3e6;
  double max_excitation_wait_seconds = 1800.0;
  // Judge only blocks at rest whose load lies within the learned rest loads (widened by
  // rest_load_tolerance); others are not judged (outside_learned_loads).
  bool limit_to_learned = true;
  // Below this |p1 - p2| [Pa] a leak hardly flows: blocks there are not counted as judged
  // (no_load), though the test still takes them.
  double no_load_pressure = 1e6;
  // A decision is judged while a block was judged at most this long ago [s]: a steps program
  // moves between its holds without the detector going blind.
  double judged_memory_seconds = 10.0;
};

class FlowBalanceDetector final : public Detector {
 public:
  FlowBalanceDetector(const FlowBalanceOptions& options, double hop_seconds);

  std::string_view name() const override { return "flow_balance"; }
  Decision update(const Observation& observation) override;
  double raise_threshold() const override { return 1.0; }
  double clear_threshold() const override { return 0.5; }
  void reset() override;
  DetectorState export_state() const override;
  void import_state(const DetectorState& state) override;
  double learning_seconds() const override {
    return options_.learning.settle_seconds + options_.learning.learn_seconds;
  }
  void resume_after_gap() override;
  std::optional<LearnedChange> learned_change() const override { return learned_change_; }

  // The layout export_state() writes (legacy_state.hpp reads the ones before).
  static constexpr int kStateVersion = 4;

 private:
  struct Hop {
    double t = kMissing;
    double opening = kMissing;    // command minus what moves the piston [of full travel]
    double load = kMissing;       // load pressure [of ps]
    double root = kMissing;       // orifice root factor of the side the valve opens to at rest
    double leak_term = kMissing;  // load / root: the opening a leak needs per unit C sqrt(ps)/Kv
                                  // (times the viscosity ratio with a temperature)
    double speed = kMissing;
    double supply = kMissing;           // supply pressure used for this hop [Pa]
    double viscosity_ratio = kMissing;  // nu(40) / nu(T) with a temperature
    bool usable = false;  // all signals present and the command within the valve's range
  };
  struct RestHop : Hop {
    std::size_t block = 0;  // block number, to regroup the learning data
  };
  // The state's names of a hop's fields (a learned rest hop's: also its block).
  template <class Record>
  static constexpr std::array<RecordField<Record>, 9> hop_fields() {
    return {record_field<&Hop::t, Record>("t"),
            record_field<&Hop::opening, Record>("opening"),
            record_field<&Hop::load, Record>("load"),
            record_field<&Hop::root, Record>("root"),
            record_field<&Hop::leak_term, Record>("leak_term"),
            record_field<&Hop::speed, Record>("speed"),
            record_field<&Hop::supply, Record>("supply"),
            record_field<&Hop::viscosity_ratio, Record>("viscosity_ratio"),
            record_field<&Hop::usable, Record>("usable")};
  }
  static constexpr std::array<RecordField<RestHop>, 10> rest_hop_fields() {
    const auto hop = hop_fields<RestHop>();
    return {hop[0], hop[1], hop[2], hop[3], hop[4],
            hop[5], hop[6], hop[7], hop[8], record_field<&RestHop::block>("block")};
  }
  static constexpr int kTerms = 6;
  using Terms = Eigen::Matrix<double, kTerms, 1>;
  Terms healthy_terms(const Hop& hop) const;
  double expected_opening(const Hop& hop) const;
  struct LoadRange {
    double low = 0.0, high = 0.0, middle = 0.0;  // of the learning data's loads on one side
  };
  LoadRange learned_range(double side);  // uses scratch_
  double robust_hop_sigma();             // uses scratch_
  // False for a hop whose command falls far short of the healthy relation: the spool crossing
  // its dead band while the piston stands still (no flow at all). A leak only ever needs more
  // opening towards the loaded chamber, so leaving these out cannot hide one.
  bool on_flow_branch(const Hop& hop) const;
  static constexpr double kOffBranchSigmas = 6.0;
  static constexpr double kMinRoot = 1e-3;  // a chamber at supply or tank: no flow to judge
  void accept(const Hop& hop, bool at_rest);
  // The sides of zero load the learning data identify (see excited_enough()).
  struct LearnedSides {
    bool positive = false, negative = false;                // offset and slope
    bool positive_curved = false, negative_curved = false;  // and curvature
  };
  void finish_learning(const LearnedSides& sides);
  // At the end of a learning period: the sides whose rests lie at loads further apart than
  // rest_load_tolerance, if together they hold min_rest_loads rests, else none; drops the rest
  // hops of a side left out and sets rest_load_low_ / rest_load_high_ from the sides kept.
  LearnedSides excited_enough();
  // The rests of the learning data on one side (+1 or -1) of zero load, and the lowest and
  // highest of their loads [of ps].
  struct RestLoads {
    std::size_t count = 0;
    double low = kMissing, high = kMissing;
  };
  RestLoads rests_on_side(double side) const;
  // The decision's judged state at source time t.
  void set_judged(Decision& decision, double t) const;
  // The learned-change probe (learned_change.hpp) over the learning data, once it is complete.
  void probe_learned_change();
  void judge_block(double t, double mean_residual, double mean_leak_term);
  double supply_for(const Observation& o, double speed);
  // Drift following (the healthy slope as a reference) only without a temperature.
  bool follows_drift() const { return !temperature_seen_; }

  FlowBalanceOptions options_;
  double hop_seconds_;
  LearningClock clock_;
  std::size_t block_hops_, min_rest_hops_;
  double piston_area_;            // A() of the rig table, computed once
  double design_slope_;           // design_leak in the normalised units of the regression
  double floor_slope_;            // min_leak in the same units
  double sizing_decay_;           // per block
  std::size_t observations_ = 0;  // the learning clock counts accepted hops, one behind
  double previous_x_ = kMissing;
  Hop before_, pending_;          // the two latest hops; pending_ is judged when the next arrives
  std::vector<RestHop> learned_;  // reserved at construction
  std::vector<double> scratch_;   // reserved at construction
  LoadRange positive_loads_, negative_loads_;
  Terms coefficients_ = Terms::Zero();
  double hop_sigma_ = kMissing;  // robust spread of one hop's residual
  double block_sigma_ = kMissing;
  // The current block.
  std::size_t block_hop_ = 0, block_rest_hops_ = 0;
  double block_residual_sum_ = 0.0, block_leak_term_sum_ = 0.0, block_load_sum_ = 0.0;
  // Hops of the current block the supply was still settling in (names why it was not judged).
  std::size_t block_unsettled_hops_ = 0;
  // Learned rest block loads [of ps], the range limit_to_learned judges within; NaN: no limit
  // (a state saved before they were learned).
  double rest_load_low_ = kMissing, rest_load_high_ = kMissing;
  // Hops of learning periods that started over for want of excitation; whether the wait ran out.
  std::size_t excitation_wait_hops_ = 0;
  bool cannot_learn_ = false;
  // Source time of the newest judged block, and why the newest unjudged one was not.
  double last_judged_t_ = kMissing;
  NotJudgedReason block_reason_ = NotJudgedReason::in_motion;
  // The added slope by least squares of residual on leak term. While the CUSUM is positive, over
  // the blocks since it last left zero (its estimate of the change time), so that the size in
  // an alarm is not diluted by healthy data; otherwise exponentially weighted.
  struct SlopeSums {
    double rl = 0.0, ll = 0.0, ll_sq = 0.0;  // sum r*l, sum l^2 (weights w), sum w^2 l^2
  };
  // The block in which the CUSUM left zero holds the change itself, so it is partly healthy
  // data: it sizes the leak only until a later block arrives.
  SlopeSums weighted_, since_change_, change_block_;
  BlockCusum cusum_;
  Decision last_;
  SupplyTracker supply_;  // from `ps`, or the chambers at rest (rule: jump)
  bool temperature_seen_ = false;
  // The healthy slope on the leak term, followed without a temperature.
  DriftReference drift_;
  std::vector<ResidualBlock> probe_blocks_;  // reserved at construction
  std::optional<LearnedChange> learned_change_;
};

}  // namespace leakmon::detect
