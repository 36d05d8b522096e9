#include "detect/feature_test.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

#include "detect/least_squares.hpp"

namespace leakmon::detect {

namespace {

// The ln of a reversal rate, finite at none.
double log_reversals(double rate) { return std::log(rate + FeatureTest::kReversalFloor); }

// Load activity below this (1e-3 of supply per hop) counts as "still": keeps the log finite.
constexpr double kActivityFloor = 1e-3;
// A hop whose load moved less than this (of supply) is at rest for the supply estimate: there
// p1 + p2 = ps + pt (MODEL.md).
constexpr double kRestActivity = 2e-3;
// Rest readings in a row far from the estimate that make a supply step (not one odd hop).
constexpr std::size_t kSupplyStepHops = 10;
// Judged blocks whose CUSUM increments can be taken back after a supply step seen through one
// chamber: the step shows at the end of the first hold that fits neither cluster (holds last up
// to 4 s, a ramp up to 5 s, and a few holds after the step may fit by chance), so within about
// 20 s; the history covers 48 s.
constexpr std::size_t kCusumHistoryBlocks = 60;

SupplyTrackerOptions supply_options(const FeatureTestOptions& o, std::size_t block_hops) {
  SupplyTrackerOptions s;
  s.configured = o.rig.ps;
  s.rule = SupplyTrackerOptions::StepRule::drift_from_anchor;
  s.confirm_readings = kSupplyStepHops;
  s.reading_seconds = o.block_seconds / static_cast<double>(block_hops);
  return s;
}

DriftReferenceOptions drift_options(const FeatureTestOptions& o, const FeaturePhysics& physics) {
  DriftReferenceOptions d;
  d.guard_seconds = o.drift_guard_seconds;
  d.window_seconds = o.drift_window_seconds;
  d.keep_seconds =
      o.drift_guard_seconds + o.drift_window_seconds + o.supply_settle_seconds + o.block_seconds;
  d.block_seconds = o.block_seconds;
  d.bound = -physics.design_shift;
  d.shrink_slope = true;
  d.slope_needs_full_window = true;
  d.hold_across_gaps = true;
  return d;
}

// The state's names of the regressors' coefficients and of the block being filled.
constexpr std::array<std::string_view, 5> kCoefficientNames = {"constant", "load", "load_squared",
                                                               "log_activity", "log_friction"};

}  // namespace

FeatureTest::FeatureTest(const FeatureTestOptions& options, const FeaturePhysics& physics,
                         double hop_seconds)
    : options_(options),
      physics_(physics),
      block_hops_(hops_in(options.block_seconds, hop_seconds)),
      clock_(options.learning, hop_seconds),
      one_chamber_(options.use_p1 != options.use_p2),
      supply_(supply_options(options, block_hops_)),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds),
             kCusumHistoryBlocks),
      drift_(drift_options(options, physics)),
      regime_(kRegimeBlocks) {
  learned_.reserve(clock_.learn_hops() / block_hops_ + 1);
  scratch_.reserve(learned_.capacity());
  candidate_.reserve(learned_.capacity());
  coefficients_[4] = physics.temperature_prior;
}

void FeatureTest::reset() {
  clock_.reset();
  learned_.clear();
  std::fill(std::begin(coefficients_), std::end(coefficients_), 0.0);
  coefficients_[4] = physics_.temperature_prior;
  block_sigma_ = kMissing;
  learned_rest_low_ = learned_rest_high_ = kMissing;
  regime_.clear();
  outside_ = false;
  learned_longest_rest_ = learned_longest_motion_ = kMissing;
  rest_run_ = motion_run_ = block_rest_run_ = block_motion_run_ = 0;
  completed_rest_run_ = completed_motion_run_ = learning_rest_run_ = learning_motion_run_ = 0;
  excitation_wait_seconds_ = 0.0;
  cannot_learn_ = false;
  waits_for_excitation_ = true;
  siegmund_threshold_ = true;
  others_ = {};
  other_count_ = 0;
  judging_other_ = -1;
  learns_other_regimes_ = true;
  candidate_.clear();
  candidate_rest_run_ = candidate_motion_run_ = 0;
  block_hop_ = block_valid_ = rest_hops_ = reversals_ = 0;
  last_direction_ = 0.0;
  sum_feature_ = sum_load_ = sum_load_squared_ = sum_activity_ = 0.0;
  sum_log_friction_ = sum_log_supply_ = 0.0;
  previous_load_ = previous_rough_load_ = last_expected_ = kMissing;
  temperature_seen_ = false;
  supply_.reset();
  chamber_supply_.reset();
  learned_supply_ = kMissing;
  cusum_.reset();
  set_threshold_for_sigma();
  drift_.clear();
  drift_.set_hold_across_gaps(true);
}

void FeatureTest::resume_after_gap() {
  drift_.clear();
  supply_.resume_after_gap();
  previous_load_ = previous_rough_load_ = kMissing;
  last_direction_ = 0.0;
  chamber_supply_.resume_after_gap();
  cusum_.forget_history();
  // The regime's blocks are on the old clock too (their residuals never reach the reference).
  regime_.clear();
  outside_ = false;
  judging_other_ = -1;
  candidate_.clear();
  candidate_rest_run_ = candidate_motion_run_ = 0;
  rest_run_ = motion_run_ = block_rest_run_ = block_motion_run_ = 0;
}

// Load pressure p1 - p2 over supply; with one chamber, that chamber's departure from mid-supply
// (the two chambers mirror each other around it at rest).
double FeatureTest::load_of(const Observation& o, double ps) const {
  const double pt = options_.rig.pt;
  if (options_.use_p1 && options_.use_p2 && !std::isnan(o.p1) && !std::isnan(o.p2)) {
    return (o.p1 - o.p2) / ps;
  }
  if (options_.use_p1 && !std::isnan(o.p1)) return (2.0 * o.p1 - ps - pt) / ps;
  if (options_.use_p2 && !std::isnan(o.p2)) return (ps + pt - 2.0 * o.p2) / ps;
  return kMissing;
}

// The supply from a `ps` observation, or from both chambers at rest; the configured value until
// either exists. A step restarts the settling clock and the drift reference (the feature's
// level before it belongs to another supply).
double FeatureTest::supply_for(const Observation& o, double load) {
  if (one_chamber_ && std::isnan(o.ps)) return supply_from_chamber(o, load);
  double reading = kMissing;
  const bool direct = !std::isnan(o.ps);
  if (direct) {
    reading = o.ps;
  } else if (options_.use_p1 && options_.use_p2 && !std::isnan(o.p1) && !std::isnan(o.p2) &&
             std::abs(load - previous_rough_load_) < kRestActivity) {
    reading = o.p1 + o.p2 - options_.rig.pt;
  }
  previous_rough_load_ = load;
  if (supply_.add(o.t, reading, direct)) drift_.clear();
  return supply_.estimate();
}

// One chamber's hold levels (ChamberSupplyTracker). The blocks judged after a step began were
// judged against the old supply: their CUSUM increments are taken back.
double FeatureTest::supply_from_chamber(const Observation& o, double load) {
  const double configured = options_.rig.ps;
  const bool still = std::abs(load - previous_rough_load_) < kRestActivity;  // false with a NaN
  previous_rough_load_ = load;
  switch (chamber_supply_.add(o.t, options_.use_p1 ? o.p1 : o.p2, still)) {
    case ChamberSupplyTracker::Event::step:
      cusum_.take_back_after(chamber_supply_.step_time());
      drift_.clear();
      break;
    case ChamberSupplyTracker::Event::estimated: {
      // Nothing was judged while waiting; the step may have begun earlier than first thought.
      cusum_.take_back_after(chamber_supply_.step_time());
      // ps + pt = 2 mid: the supply moved by twice mid-supply's shift since learning.
      const double learned = std::isnan(learned_supply_) ? configured : learned_supply_;
      supply_.set_after_step(
          o.t, std::max(learned + 2.0 * chamber_supply_.mid_shift(), 0.1 * configured));
      drift_.clear();
      break;
    }
    case ChamberSupplyTracker::Event::none:
      break;
  }
  return supply_.estimate();
}

double FeatureTest::expected_feature(const Block& b) const {
  return coefficients_[0] + coefficients_[1] * b.load + coefficients_[2] * b.load_squared +
         coefficients_[3] * b.log_activity + coefficients_[4] * b.log_friction +
         physics_.supply_exponent * b.log_supply;
}

// Adds one hop; true when a block completed with enough valid hops (then `completed` holds it).
bool FeatureTest::add_to_block(const Observation& o, double temp, double feature, double load,
                               double supply, Block& completed) {
  const double change = load - previous_load_;
  const double activity = std::abs(change);
  previous_load_ = load;
  if (!std::isnan(activity)) count_run(activity < kRestActivity);
  if (activity >= kRestActivity) {
    const double direction = change > 0.0 ? 1.0 : -1.0;
    if (last_direction_ != 0.0 && direction != last_direction_) ++reversals_;
    last_direction_ = direction;
  }
  const bool settled = supply_.settled(o.t) && !chamber_supply_.awaiting();
  const bool temperature_ok = !temperature_seen_ || !std::isnan(temp);
  if (!std::isnan(feature) && !std::isnan(activity) && settled && temperature_ok) {
    sum_feature_ += feature;
    sum_load_ += load;
    sum_load_squared_ += load * load;
    sum_activity_ += activity;
    sum_log_supply_ += std::log(supply);
    // The viscous friction's share of the damping, b(T) = b (0.5 + 0.5 / r) (MODEL.md).
    if (temperature_seen_) {
      sum_log_friction_ -= std::log(sim::friction_factor(physics_.oil.ratio(temp)));
    }
    ++block_valid_;
    if (activity < kRestActivity) ++rest_hops_;
  }
  if (++block_hop_ < block_hops_) return false;
  const bool enough = 2 * block_valid_ >= block_hops_;
  if (enough) {
    const double n = static_cast<double>(block_valid_);
    completed = {o.t,
                 sum_feature_ / n,
                 sum_load_ / n,
                 sum_load_squared_ / n,
                 std::log(sum_activity_ / n + kActivityFloor),
                 sum_log_friction_ / n,
                 sum_log_supply_ / n,
                 static_cast<double>(rest_hops_) / n,
                 static_cast<double>(reversals_) / options_.block_seconds};
  }
  completed_rest_run_ = block_rest_run_;
  completed_motion_run_ = block_motion_run_;
  // A run that goes on reaches into the next block.
  block_rest_run_ = rest_run_;
  block_motion_run_ = motion_run_;
  block_hop_ = block_valid_ = rest_hops_ = reversals_ = 0;
  sum_feature_ = sum_load_ = sum_load_squared_ = sum_activity_ = 0.0;
  sum_log_friction_ = sum_log_supply_ = 0.0;
  return enough;
}

void FeatureTest::finish_learning() {
  clock_.set_learned();
  learned_supply_ = supply_.estimate();
  if (one_chamber_) chamber_supply_.learn();
  if (learned_.size() < 2 * kRegressors) return;  // too little data: never judges
  const double exponent = physics_.supply_exponent;
  auto response = [exponent](const Block& b) { return b.feature - exponent * b.log_supply; };
  // First without the temperature: the spread that weighs the prior.
  LeastSquares<4> plain;
  for (const auto& b : learned_) {
    plain.add(Eigen::Vector4d(1.0, b.load, b.load_squared, b.log_activity), response(b));
  }
  const Eigen::Vector4d beta4 = plain.solve();
  for (int i = 0; i < 4; ++i) coefficients_[i] = beta4[i];
  coefficients_[4] = physics_.temperature_prior;
  if (temperature_seen_) {
    // The prior on the temperature coefficient as one pseudo-observation of weight
    // sigma^2 / sigma_prior^2: what the learning period's temperature range identifies
    // outweighs it, a constant temperature leaves it in place.
    using Vector5 = Eigen::Matrix<double, kRegressors, 1>;
    LeastSquares<kRegressors> fit;
    for (const auto& b : learned_) {
      Vector5 x;
      x << 1.0, b.load, b.load_squared, b.log_activity, b.log_friction;
      fit.add(x, response(b));
    }
    // Neighbouring blocks share an operating point: the data's weight is that of its
    // long-run (AR(1)) variance, not of as many independent blocks.
    double sum_sq = 0.0, sum_lag = 0.0, previous = kMissing;
    for (const auto& b : learned_) {
      const double r =
          response(b) - beta4.dot(Eigen::Vector4d(1.0, b.load, b.load_squared, b.log_activity));
      sum_sq += r * r;
      if (!std::isnan(previous)) sum_lag += r * previous;
      previous = r;
    }
    const double rho = sum_sq > 0.0 ? lag_one_correlation(sum_lag, sum_sq) : 0.0;
    const double weight = std::sqrt(plain.residual_variance(beta4) * (1.0 + rho) / (1.0 - rho)) /
                          std::max(physics_.temperature_prior_sigma, 1e-9);
    Vector5 prior = Vector5::Zero();
    prior[4] = weight;
    fit.add(prior, weight * physics_.temperature_prior);
    const Vector5 beta = fit.solve();
    for (int i = 0; i < kRegressors; ++i) coefficients_[i] = beta[i];
  }
  double sum_sq = 0.0, sum_lag = 0.0, previous = kMissing;
  for (const auto& b : learned_) {
    const double r = b.feature - expected_feature(b);
    drift_.add(b.t, r);
    sum_sq += r * r;
    if (!std::isnan(previous)) sum_lag += r * previous;
    previous = r;
  }
  const auto n = learned_.size();
  const double sigma = std::sqrt(sum_sq / static_cast<double>(n - kRegressors));
  block_sigma_ = cusum_block_sigma(sigma, n, lag_one_correlation(sum_lag, sum_sq));
  set_threshold_for_sigma();

  // The regime learned: the range of the share of hops at rest over kRegimeBlocks blocks.
  if (!(options_.regime_tolerance > 0.0) || n < kRegimeBlocks) return;
  for (const auto& b : learned_) {
    if (std::isnan(b.rest_share)) return;  // blocks of a state from before issue 23
  }
  const WindowRange rest = window_mean_range(learned_, &Block::rest_share);
  learned_rest_low_ = rest.low;
  learned_rest_high_ = rest.high;
  learned_longest_rest_ = static_cast<double>(learning_rest_run_) * hop_seconds();
  learned_longest_motion_ = static_cast<double>(learning_motion_run_) * hop_seconds();
}

// The lowest and highest mean of a block field over every kRegimeBlocks consecutive blocks (a
// running sum; the blocks hold at least kRegimeBlocks).
FeatureTest::WindowRange FeatureTest::window_mean_range(std::span<const Block> blocks,
                                                        double Block::*field) {
  WindowRange range{1e300, -1e300};
  double sum = 0.0;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    sum += blocks[i].*field;
    if (i >= kRegimeBlocks) sum -= blocks[i - kRegimeBlocks].*field;
    if (i + 1 < kRegimeBlocks) continue;
    const double mean = sum / static_cast<double>(kRegimeBlocks);
    range.low = std::min(range.low, mean);
    range.high = std::max(range.high, mean);
  }
  return range;
}

FeatureTest::WindowRange FeatureTest::reversal_range(std::span<const Block> blocks) {
  const WindowRange range = window_mean_range(blocks, &Block::reversal_rate);
  if (!(range.low <= range.high)) return {kMissing, kMissing};
  return range;
}

void FeatureTest::count_run(bool at_rest) {
  if (at_rest) {
    ++rest_run_;
    motion_run_ = 0;
  } else {
    ++motion_run_;
    rest_run_ = 0;
  }
  block_rest_run_ = std::max(block_rest_run_, rest_run_);
  block_motion_run_ = std::max(block_motion_run_, motion_run_);
}

bool FeatureTest::runs_outside() const {
  if (!runs_known()) return false;
  const double rest = static_cast<double>(completed_rest_run_) * hop_seconds();
  const double motion = static_cast<double>(completed_motion_run_) * hop_seconds();
  return rest > kRunFactor * learned_longest_rest_ ||
         motion > kRunFactor * learned_longest_motion_ + kMotionRunSlackSeconds;
}

// The increments are Gaussian log-likelihood ratios once the spread is known, so the threshold
// follows Siegmund's approximation at the designed shift in spreads (learning_schedule.hpp)
// instead of Lorden's bound, which was 2-3 nats higher than the target needs.
void FeatureTest::set_threshold_for_sigma() {
  const double lorden = cusum_threshold_for(options_.false_alarms_per_hour, options_.block_seconds);
  if (!physics_.threshold_from_spread || !siegmund_threshold_ || std::isnan(block_sigma_) ||
      !(block_sigma_ > 0.0)) {
    cusum_.set_threshold(lorden);
    return;
  }
  cusum_.set_threshold(
      cusum_threshold_for_shift(options_.false_alarms_per_hour, options_.block_seconds,
                                (physics_.design_shift - physics_.null_shift) / block_sigma_));
}

// The spread of the learning period's block log load activity (10 % to 90 % quantile): a
// program that rings the mode (steps) moves and rests, and its blocks span both; a hold rests
// throughout, a sine or a triangle moves at one steady pace. The regressors of the feature's
// model are identified only in the first case (a hold makes the load and the activity
// constants), and the steady programs the regime test recognises against it.
bool FeatureTest::one_program_so_far() const {
  if (!waits_for_excitation_ || !(options_.min_excitation_range > 0.0)) return true;
  if (static_cast<double>(learning_rest_run_) * hop_seconds() > kLongestLearningRestSeconds) {
    return false;
  }
  if (learned_.size() < kRegimeBlocks) return true;
  double sum = 0.0;
  for (std::size_t age = 0; age < kRegimeBlocks; ++age) {
    sum += learned_[learned_.size() - 1 - age].rest_share;
  }
  return !(sum < kLearningRestShare * static_cast<double>(kRegimeBlocks));
}

bool FeatureTest::excited_enough() {
  if (!waits_for_excitation_ || !(options_.min_excitation_range > 0.0)) return true;
  scratch_.clear();
  for (const auto& b : learned_) scratch_.push_back(b.log_activity);  // capacity reserved
  if (scratch_.size() < 2 * kRegressors) return true;  // too little data: finish_learning says so
  const auto at = [this](double q) {
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(scratch_.size() - 1));
    std::nth_element(scratch_.begin(), scratch_.begin() + k, scratch_.end());
    return scratch_[static_cast<std::size_t>(k)];
  };
  const double low = at(0.1), high = at(0.9);
  if (high - low < options_.min_excitation_range) return false;
  // One program that moves and rests: no hold within the period, and no window of it (a sine,
  // a sweep) that hardly rests.
  if (static_cast<double>(learning_rest_run_) * hop_seconds() > kLongestLearningRestSeconds) {
    return false;
  }
  if (learned_.size() < kRegimeBlocks) return true;
  double sum = 0.0;
  for (std::size_t i = 0; i < learned_.size(); ++i) {
    sum += learned_[i].rest_share;
    if (i >= kRegimeBlocks) sum -= learned_[i - kRegimeBlocks].rest_share;
    if (i + 1 >= kRegimeBlocks && sum < kLearningRestShare * static_cast<double>(kRegimeBlocks)) {
      return false;
    }
  }
  return true;
}

// The share of hops at rest over the last kRegimeBlocks blocks against the learned range,
// widened by regime_tolerance: steps move and rest, a sine, sweep or triangle hardly rests, a
// hold does nothing else, and a leak changes none of it. On entering an excursion the blocks
// since it began (those in the ring) are taken back out of the CUSUM and never reach the drift
// reference; blocks leaving the ring in the regime do.
bool FeatureTest::outside_regime(const Block& block) {
  if (!regime_known()) return false;
  if (regime_.full() && !std::isnan(regime_.oldest().residual)) {
    drift_.add(regime_.oldest().t, regime_.oldest().residual);
  }
  regime_.push({block.t, block.rest_share, kMissing, block.log_activity, block.reversal_rate});
  bool outside = outside_;  // after a gap: too few blocks to say from the share
  if (regime_.full()) {
    double sum = 0.0;
    for (std::size_t i = 0; i < regime_.size(); ++i) sum += regime_.oldest(i).share;
    const double share = sum / static_cast<double>(regime_.size());
    // Back in the regime only well inside: a program near the edge would otherwise flicker in
    // and out, judged by halves.
    const double margin = outside_ ? 0.5 * options_.regime_tolerance : options_.regime_tolerance;
    outside = share < learned_rest_low_ - margin || share > learned_rest_high_ + margin;
  }
  // A run longer than the program learned says the change before the share does.
  outside = outside || runs_outside();
  if (outside && !outside_) {
    cusum_.take_back_after(regime_.oldest().t - 0.5 * options_.block_seconds);
    // The ring's blocks were judged in the new program: none of them enters the reference.
    for (std::size_t age = 0; age < regime_.size(); ++age) regime_.newest(age).residual = kMissing;
  }
  outside_ = outside;
  return outside;
}

void FeatureTest::take_back_ring() {
  if (regime_.empty()) return;
  cusum_.take_back_after(regime_.oldest().t - 0.5 * options_.block_seconds);
  for (std::size_t age = 0; age < regime_.size(); ++age) regime_.newest(age).residual = kMissing;
}

// The ring's means against each learned other program; the one judging stays on with the
// full tolerances, another is entered only well inside them (no flicker between two programs
// near each other's edges).
int FeatureTest::other_regime_of_ring() const {
  if (other_count_ == 0 || !regime_.full()) return -1;
  double share = 0.0, activity = 0.0, reversals = 0.0;
  for (std::size_t i = 0; i < regime_.size(); ++i) {
    share += regime_.oldest(i).share;
    activity += regime_.oldest(i).activity;
    reversals += regime_.oldest(i).reversals;
  }
  share /= static_cast<double>(regime_.size());
  activity /= static_cast<double>(regime_.size());
  reversals /= static_cast<double>(regime_.size());
  if (std::isnan(share) || std::isnan(activity)) return -1;  // a ring from a state before it
  const double rest = static_cast<double>(completed_rest_run_) * hop_seconds();
  const double motion = static_cast<double>(completed_motion_run_) * hop_seconds();
  const auto fits = [&](std::size_t k) {
    const OtherRegime& r = others_[k];
    const double widen = static_cast<int>(k) == judging_other_ ? 1.0 : 0.5;
    const double share_margin = widen * options_.regime_tolerance;
    const double activity_margin = widen * kActivityTolerance;
    // A regime learned without the rate, or a ring from a state before it: as then.
    const bool frequency_fits =
        std::isnan(r.reversals_low) || std::isnan(reversals) ||
        (log_reversals(reversals) >= log_reversals(r.reversals_low) - widen * kFrequencyTolerance &&
         log_reversals(reversals) <= log_reversals(r.reversals_high) + widen * kFrequencyTolerance);
    return frequency_fits && share >= r.rest_low - share_margin &&
           share <= r.rest_high + share_margin && activity >= r.activity_low - activity_margin &&
           activity <= r.activity_high + activity_margin &&
           rest <= kRunFactor * r.longest_rest + kMotionRunSlackSeconds &&
           motion <= kRunFactor * r.longest_motion + kMotionRunSlackSeconds;
  };
  if (judging_other_ >= 0 && fits(static_cast<std::size_t>(judging_other_))) return judging_other_;
  for (std::size_t k = 0; k < other_count_; ++k) {
    if (fits(k)) return static_cast<int>(k);
  }
  return -1;
}

// A program that is neither the first nor a learned other one: its blocks are gathered for a
// learning period. A hold (a rest run longer than any level of steps) is not learned: it hardly
// rings the mode, and a leak's flow there depends on where it holds. A period whose rest share
// or activity moves by more than one program scatters began in another program: it keeps only
// its latest blocks.
void FeatureTest::learn_other(const Block& block) {
  if (!learns_other_regimes_ || other_count_ >= kMaxOtherRegimes ||
      !(options_.regime_tolerance > 0.0)) {
    return;
  }
  if (static_cast<double>(completed_rest_run_) * hop_seconds() > kLongestLearningRestSeconds) {
    candidate_.clear();
    candidate_rest_run_ = candidate_motion_run_ = 0;
    return;
  }
  candidate_.push_back(block);  // capacity reserved; finished before it fills
  candidate_rest_run_ = std::max(candidate_rest_run_, completed_rest_run_);
  candidate_motion_run_ = std::max(candidate_motion_run_, completed_motion_run_);
  if (candidate_.size() >= kRegimeBlocks) {
    const WindowRange share = window_mean_range(candidate_, &Block::rest_share);
    const WindowRange activity = window_mean_range(candidate_, &Block::log_activity);
    const WindowRange reversals = reversal_range(candidate_);  // NaN: compared as then
    if (share.high - share.low > 2.0 * options_.regime_tolerance ||
        activity.high - activity.low > 2.0 * kActivityTolerance ||
        log_reversals(reversals.high) - log_reversals(reversals.low) > 2.0 * kFrequencyTolerance) {
      const auto keep = static_cast<std::ptrdiff_t>(kRegimeBlocks / 2);
      candidate_.erase(candidate_.begin(), candidate_.end() - keep);
      candidate_rest_run_ = completed_rest_run_;
      candidate_motion_run_ = completed_motion_run_;
      return;
    }
  }
  if (candidate_.size() >= clock_.learn_hops() / block_hops_) finish_other();
}

// Judged by that program's baseline, in its spreads; its residuals stay out of the drift
// reference, which follows the first program's.
void FeatureTest::judge_other(const Block& block, std::size_t other, double reference) {
  const OtherRegime& r = others_[other];
  last_expected_ = other_expected(r, block) + reference - r.reference;
  const double null_shift = physics_.null_shift / r.sigma;
  const double shift = physics_.design_shift / r.sigma;
  const double z = (block.feature - last_expected_) / r.sigma;
  cusum_.add(block.t, (shift - null_shift) * (z - (shift + null_shift) / 2.0));
}

// Before the steps are learned (or when they cannot be: a rig that runs sines for hours), a
// program that hardly rests (its rest share over kRegimeBlocks blocks below what a learning
// period of steps shows) is learned and judged as another regime all the same; the steps'
// learning goes on beside it. There is no drift reference yet, and the load and activity terms
// are pulled towards none.
bool FeatureTest::judge_without_steps(bool completed, const Block& block, Verdict& verdict) {
  if (!learns_other_regimes_ || !waits_for_excitation_ || !(options_.regime_tolerance > 0.0) ||
      !(options_.min_excitation_range > 0.0)) {
    return false;
  }
  if (completed && !chamber_supply_.awaiting()) {
    regime_.push({block.t, block.rest_share, kMissing, block.log_activity, block.reversal_rate});
    bool moving = false;
    if (regime_.full()) {
      double share = 0.0;
      for (std::size_t i = 0; i < regime_.size(); ++i) share += regime_.oldest(i).share;
      moving = share < kLearningRestShare * static_cast<double>(regime_.size());
    }
    const int other = moving ? other_regime_of_ring() : -1;
    if (other != judging_other_) {
      if (judging_other_ >= 0) take_back_ring();
      judging_other_ = other;
      candidate_.clear();
      candidate_rest_run_ = candidate_motion_run_ = 0;
    }
    if (other >= 0) {
      judge_other(block, static_cast<std::size_t>(other), 0.0);
    } else if (moving) {
      learn_other(block);
    } else {
      candidate_.clear();
      candidate_rest_run_ = candidate_motion_run_ = 0;
    }
  }
  if (judging_other_ < 0) return false;
  verdict.learning = false;
  verdict.learning_hops_left = kMissing;
  verdict.not_judged = NotJudgedReason::none;
  verdict.expected = last_expected_;
  verdict.score = cusum_.normalised();
  return true;
}

double FeatureTest::other_expected(const OtherRegime& r, const Block& b) const {
  return r.constant + r.load * b.load + r.load_squared * b.load_squared +
         r.log_activity * b.log_activity + coefficients_[4] * b.log_friction +
         physics_.supply_exponent * b.log_supply;
}

// The other program's baseline from its learning period: the constant is what the excitation
// sets; the load and activity terms are the first program's as far as this period's blocks
// spanned too little of them to say (one pseudo-observation each, weighing as much as the data
// when the regressor's spread is kPriorSpread).
void FeatureTest::finish_other() {
  const std::size_t n = candidate_.size();
  if (n < 2 * kRegressors) return;
  const auto response = [this](const Block& b) {
    return b.feature - physics_.supply_exponent * b.log_supply - coefficients_[4] * b.log_friction;
  };
  LeastSquares<4> fit;
  for (const auto& b : candidate_) {
    fit.add(Eigen::Vector4d(1.0, b.load, b.load_squared, b.log_activity), response(b));
  }
  constexpr std::array<double, 3> kPriorSpread = {0.1, 0.03, 0.3};
  for (int j = 1; j < 4; ++j) {
    const double w =
        std::sqrt(static_cast<double>(n)) * kPriorSpread[static_cast<std::size_t>(j - 1)];
    Eigen::Vector4d row = Eigen::Vector4d::Zero();
    row[j] = w;
    fit.add(row, w * coefficients_[j]);
  }
  const Eigen::Vector4d beta = fit.solve();
  OtherRegime r{};
  r.constant = beta[0];
  r.load = beta[1];
  r.load_squared = beta[2];
  r.log_activity = beta[3];
  double sum_sq = 0.0, sum_lag = 0.0, previous = kMissing;
  for (const auto& b : candidate_) {
    const double e = b.feature - other_expected(r, b);
    sum_sq += e * e;
    if (!std::isnan(previous)) sum_lag += e * previous;
    previous = e;
  }
  const double sigma = std::sqrt(sum_sq / static_cast<double>(n - 4));
  r.sigma = cusum_block_sigma(sigma, n, lag_one_correlation(sum_lag, sum_sq));
  if (!(r.sigma > 0.0)) {
    candidate_.clear();
    return;
  }
  r.reference =
      clock_.learned() && !cannot_learn_ && block_sigma_ > 0.0
          ? drift_.reference(candidate_.back().t, block_sigma_, temperature_seen_, anchored_until())
          : 0.0;
  const WindowRange share = window_mean_range(candidate_, &Block::rest_share);
  const WindowRange activity = window_mean_range(candidate_, &Block::log_activity);
  r.rest_low = share.low;
  r.rest_high = share.high;
  r.activity_low = activity.low;
  r.activity_high = activity.high;
  r.longest_rest = static_cast<double>(candidate_rest_run_) * hop_seconds();
  r.longest_motion = static_cast<double>(candidate_motion_run_) * hop_seconds();
  const WindowRange reversals = reversal_range(candidate_);
  r.reversals_low = reversals.low;
  r.reversals_high = reversals.high;
  others_[other_count_++] = r;
  candidate_.clear();
  candidate_rest_run_ = candidate_motion_run_ = 0;
}

// A healthy block's residual for the drift reference: through the regime ring when the block
// went into it (it enters once kRegimeBlocks later blocks showed no excursion), else at once.
void FeatureTest::add_to_reference(const Block& block, double residual) {
  if (regime_known() && !regime_.empty() && regime_.newest().t == block.t) {
    regime_.newest().residual = residual;
  } else {
    drift_.add(block.t, residual);
  }
}

double FeatureTest::anchored_until() const {
  return supply_.step_time() + options_.supply_settle_seconds;
}

FeatureTest::Verdict FeatureTest::update(const Observation& o, double feature) {
  Verdict verdict;
  const bool past_settling = clock_.count_hop();
  if (!clock_.learned()) verdict.learning_hops_left = clock_.hops_left();
  if (!past_settling) return verdict;
  const double temp = physics_.uses_temperature ? o.temp : kMissing;
  if (!std::isnan(temp)) temperature_seen_ = true;

  const double rough_load = load_of(o, options_.rig.ps);
  const double supply = supply_for(o, rough_load);
  Block block{};
  const bool completed = add_to_block(o, temp, feature, load_of(o, supply), supply, block);
  if (!clock_.learned()) {
    if (completed) {
      learned_.push_back(block);  // capacity reserved: never reallocates
      learning_rest_run_ = std::max(learning_rest_run_, completed_rest_run_);
      learning_motion_run_ = std::max(learning_motion_run_, completed_motion_run_);
    }
    const bool over = clock_.period_over();
    // A hold or another program within the period: discarded at once, so that the next period
    // begins with the program that follows rather than up to a period later.
    const bool broken = completed && !over && !one_program_so_far();
    if (over || broken) {
      if (over && excited_enough()) {
        finish_learning();
      } else if (excitation_wait_seconds_ >= options_.max_excitation_wait_seconds) {
        // A baseline of an unexcited rig would read the first excited program as a leak.
        cannot_learn_ = true;
        learned_.clear();
        clock_.set_learned();
      } else {
        excitation_wait_seconds_ +=
            over ? options_.learning.learn_seconds
                 : static_cast<double>(clock_.learning_hop() + 1) * hop_seconds();
        learned_.clear();
        learning_rest_run_ = learning_motion_run_ = 0;
        clock_.restart_period();
        verdict.learning_hops_left = clock_.hops_left();
      }
    }
    if (excitation_wait_seconds_ > 0.0 && !clock_.learned()) {
      verdict.not_judged = NotJudgedReason::waiting_for_excitation;
    }
    if (!cannot_learn_) {
      judge_without_steps(completed, block, verdict);
      return verdict;
    }
  }
  verdict.learning = false;
  if (cannot_learn_) {
    if (!judge_without_steps(completed, block, verdict)) {
      verdict.not_judged = NotJudgedReason::cannot_learn;
    }
    return verdict;
  }
  if (std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) return verdict;
  if (completed && !chamber_supply_.awaiting()) {
    const double residual = block.feature - expected_feature(block);
    const double reference =
        drift_.reference(block.t, block_sigma_, temperature_seen_, anchored_until());
    last_expected_ = expected_feature(block) + reference;
    const double step_time = supply_.step_time();
    const bool anchoring =
        !std::isnan(step_time) && block.t - step_time < options_.supply_settle_seconds;
    if (anchoring) {
      drift_.add(block.t, residual);
    } else if (outside_regime(block)) {
      const int other = other_regime_of_ring();
      if (other != judging_other_) {
        if (judging_other_ >= 0) take_back_ring();
        judging_other_ = other;
        candidate_.clear();
        candidate_rest_run_ = candidate_motion_run_ = 0;
      }
      if (other < 0) {
        learn_other(block);
        verdict.not_judged = NotJudgedReason::outside_learned_regime;
      } else {
        judge_other(block, static_cast<std::size_t>(other), reference);
      }
    } else {
      if (judging_other_ >= 0) {
        take_back_ring();
        judging_other_ = -1;
      }
      candidate_.clear();
      candidate_rest_run_ = candidate_motion_run_ = 0;
      // Log-likelihood ratio of "the mean residual is design_shift" against "null_shift", per
      // block.
      const double null_shift = physics_.null_shift / block_sigma_;
      const double shift = physics_.design_shift / block_sigma_;  // more negative
      const double z = (residual - reference) / block_sigma_;
      cusum_.add(block.t, (shift - null_shift) * (z - (shift + null_shift) / 2.0));
      // Blocks under suspicion stay out of the reference: a leak is never learned as drift.
      if (cusum_.normalised() < 0.5) add_to_reference(block, residual);
    }
  } else if (outside_ && judging_other_ < 0) {
    verdict.not_judged = NotJudgedReason::outside_learned_regime;
  }
  verdict.expected = last_expected_;
  verdict.score = cusum_.normalised();
  return verdict;
}

void FeatureTest::save(DetectorState& state, std::string_view prefix) const {
  const auto key = [&](std::string_view name) { return state_key(prefix, name); };
  clock_.save(state, key("learning"));
  put_records(state, key("learned"), std::span<const Block>(learned_), kBlockFields);
  for (int i = 0; i < kRegressors; ++i) {
    state.put(key("coefficient." + std::string(kCoefficientNames[static_cast<std::size_t>(i)])),
              coefficients_[i]);
  }
  state.put(key("block_sigma"), block_sigma_);
  state.put(key("regime.rest_low"), learned_rest_low_);
  state.put(key("regime.rest_high"), learned_rest_high_);
  save_ring(state, key("regime.blocks"), regime_, kRegimeFields);
  state.put(key("regime.outside"), outside_ ? 1.0 : 0.0);
  state.put(key("regime.longest_rest"), learned_longest_rest_);
  state.put(key("regime.longest_motion"), learned_longest_motion_);
  state.put_count(key("run.rest_hops"), rest_run_);
  state.put_count(key("run.motion_hops"), motion_run_);
  state.put_count(key("block.rest_run"), block_rest_run_);
  state.put_count(key("block.motion_run"), block_motion_run_);
  state.put_count(key("excitation.rest_run"), learning_rest_run_);
  state.put_count(key("excitation.motion_run"), learning_motion_run_);
  state.put(key("excitation.wait_seconds"), excitation_wait_seconds_);
  state.put(key("excitation.cannot_learn"), cannot_learn_ ? 1.0 : 0.0);
  state.put(key("excitation.waits"), waits_for_excitation_ ? 1.0 : 0.0);
  put_records(state, key("others"), std::span<const OtherRegime>(others_.data(), other_count_),
              kOtherRegimeFields);
  state.put(key("others.judging"), static_cast<double>(judging_other_));
  state.put(key("others.learns"), learns_other_regimes_ ? 1.0 : 0.0);
  put_records(state, key("others.candidate"), std::span<const Block>(candidate_), kBlockFields);
  state.put_count(key("others.candidate_rest_run"), candidate_rest_run_);
  state.put_count(key("others.candidate_motion_run"), candidate_motion_run_);
  // Only where the physics takes the threshold from the spread (index_cusum's layout lacks it).
  if (physics_.threshold_from_spread) {
    state.put(key("threshold.siegmund"), siegmund_threshold_ ? 1.0 : 0.0);
  }
  state.put_count(key("block.rest_hops"), rest_hops_);
  state.put_count(key("block.reversals"), reversals_);
  state.put(key("run.direction"), last_direction_);
  state.put_count(key("block.hops"), block_hop_);
  state.put_count(key("block.valid"), block_valid_);
  state.put(key("block.sum_feature"), sum_feature_);
  state.put(key("block.sum_load"), sum_load_);
  state.put(key("block.sum_load_squared"), sum_load_squared_);
  state.put(key("block.sum_activity"), sum_activity_);
  state.put(key("block.sum_log_friction"), sum_log_friction_);
  state.put(key("block.sum_log_supply"), sum_log_supply_);
  state.put(key("previous_load"), previous_load_);
  state.put(key("previous_rough_load"), previous_rough_load_);
  state.put(key("last_expected"), last_expected_);
  state.put(key("temperature_seen"), temperature_seen_ ? 1.0 : 0.0);
  supply_.save(state, key("supply"));
  chamber_supply_.save(state, key("chamber_supply"));
  state.put(key("learned_supply"), learned_supply_);
  state.put(key("drift_holds_across_gaps"), drift_.holds_across_gaps() ? 1.0 : 0.0);
  cusum_.save(state, key("cusum"));
  drift_.save(state, key("drift"));
}

void FeatureTest::restore(const DetectorState& state, std::string_view prefix) {
  const auto key = [&](std::string_view name) { return state_key(prefix, name); };
  reset();
  clock_.restore(state, key("learning"));
  const std::size_t learned = record_count(state, key("learned"), kBlockFields);
  if (learned > learned_.capacity()) {
    throw StateError("more learned blocks than this configuration learns");
  }
  learned_.resize(learned);  // within the reserved capacity
  get_records(state, key("learned"), kBlockFields, std::span<Block>(learned_));
  for (int i = 0; i < kRegressors; ++i) {
    coefficients_[i] = state.get(
        key("coefficient." + std::string(kCoefficientNames[static_cast<std::size_t>(i)])));
  }
  block_sigma_ = state.get(key("block_sigma"));
  siegmund_threshold_ =
      !physics_.threshold_from_spread || state.get(key("threshold.siegmund")) != 0.0;
  set_threshold_for_sigma();  // before the CUSUM's value, which its cap bounds
  learned_rest_low_ = state.get(key("regime.rest_low"));
  learned_rest_high_ = state.get(key("regime.rest_high"));
  restore_ring(state, key("regime.blocks"), regime_, kRegimeFields);
  outside_ = state.get(key("regime.outside")) != 0.0;
  learned_longest_rest_ = state.get(key("regime.longest_rest"));
  learned_longest_motion_ = state.get(key("regime.longest_motion"));
  rest_run_ = state.get_count(key("run.rest_hops"));
  motion_run_ = state.get_count(key("run.motion_hops"));
  block_rest_run_ = state.get_count(key("block.rest_run"));
  block_motion_run_ = state.get_count(key("block.motion_run"));
  learning_rest_run_ = state.get_count(key("excitation.rest_run"));
  learning_motion_run_ = state.get_count(key("excitation.motion_run"));
  excitation_wait_seconds_ = state.get(key("excitation.wait_seconds"));
  cannot_learn_ = state.get(key("excitation.cannot_learn")) != 0.0;
  waits_for_excitation_ = state.get(key("excitation.waits")) != 0.0;
  other_count_ = record_count(state, key("others"), kOtherRegimeFields);
  if (other_count_ > kMaxOtherRegimes) throw StateError("more other regimes than are learned");
  get_records(state, key("others"), kOtherRegimeFields,
              std::span<OtherRegime>(others_.data(), other_count_));
  const double judging = state.get(key("others.judging"));
  if (!(judging >= -1.0) || !(judging < static_cast<double>(other_count_)) ||
      std::floor(judging) != judging) {
    throw StateError("the judging regime is not a learned one");
  }
  judging_other_ = static_cast<int>(judging);
  learns_other_regimes_ = state.get(key("others.learns")) != 0.0;
  const std::size_t candidate = record_count(state, key("others.candidate"), kBlockFields);
  if (candidate > candidate_.capacity()) {
    throw StateError("more candidate blocks than this configuration learns");
  }
  candidate_.resize(candidate);  // within the reserved capacity
  get_records(state, key("others.candidate"), kBlockFields, std::span<Block>(candidate_));
  candidate_rest_run_ = state.get_count(key("others.candidate_rest_run"));
  candidate_motion_run_ = state.get_count(key("others.candidate_motion_run"));
  rest_hops_ = state.get_count(key("block.rest_hops"));
  reversals_ = state.get_count(key("block.reversals"));
  last_direction_ = state.get(key("run.direction"));
  if (last_direction_ != 0.0 && last_direction_ != 1.0 && last_direction_ != -1.0) {
    throw StateError("the load's last direction is neither -1, 0 nor 1");
  }
  block_hop_ = state.get_count(key("block.hops"));
  block_valid_ = state.get_count(key("block.valid"));
  if (block_hop_ >= block_hops_ || block_valid_ > block_hop_ || rest_hops_ > block_valid_ ||
      reversals_ > block_hop_) {
    throw StateError("block position out of range");
  }
  sum_feature_ = state.get(key("block.sum_feature"));
  sum_load_ = state.get(key("block.sum_load"));
  sum_load_squared_ = state.get(key("block.sum_load_squared"));
  sum_activity_ = state.get(key("block.sum_activity"));
  sum_log_friction_ = state.get(key("block.sum_log_friction"));
  sum_log_supply_ = state.get(key("block.sum_log_supply"));
  previous_load_ = state.get(key("previous_load"));
  previous_rough_load_ = state.get(key("previous_rough_load"));
  last_expected_ = state.get(key("last_expected"));
  temperature_seen_ = state.get(key("temperature_seen")) != 0.0;
  supply_.restore(state, key("supply"));
  chamber_supply_.restore(state, key("chamber_supply"));
  learned_supply_ = state.get(key("learned_supply"));
  drift_.set_hold_across_gaps(state.get(key("drift_holds_across_gaps")) != 0.0);
  cusum_.restore(state, key("cusum"));
  drift_.restore(state, key("drift"));
}

}  // namespace leakmon::detect
