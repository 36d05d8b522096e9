#include "detect/flow_balance_detector.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "detect/least_squares.hpp"
#include "detect/legacy_state.hpp"

namespace leakmon::detect {

namespace {

double sign_of(double value) { return value > 0.0 ? 1.0 : (value < 0.0 ? -1.0 : 0.0); }

SupplyTrackerOptions supply_options(const FlowBalanceOptions& o, double hop_seconds) {
  SupplyTrackerOptions s;
  s.configured = o.rig.ps;
  s.rule = SupplyTrackerOptions::StepRule::jump;
  s.reading_seconds = hop_seconds;
  return s;
}

// The reference is a slope on the leak term: blocks weighted by its square, the fitted line's
// value now extrapolated at most by the leak floor (a trend fitted to a few noisy blocks can
// never carry the reference further than a leak of interest).
DriftReferenceOptions drift_options(const FlowBalanceOptions& o, double floor_slope) {
  DriftReferenceOptions d;
  d.guard_seconds = o.drift_guard_seconds;
  d.window_seconds = o.drift_window_seconds;
  d.keep_seconds = o.drift_guard_seconds + o.drift_window_seconds + o.block_seconds;
  d.block_seconds = o.block_seconds;
  d.bound = floor_slope;
  return d;
}

}  // namespace

FlowBalanceDetector::FlowBalanceDetector(const FlowBalanceOptions& options, double hop_seconds)
    : options_(options),
      hop_seconds_(hop_seconds),
      clock_(options.learning, hop_seconds),
      block_hops_(hops_in(options.block_seconds, hop_seconds)),
      min_rest_hops_(std::max<std::size_t>(
          static_cast<std::size_t>(
              std::ceil(options.min_rest_fraction * static_cast<double>(block_hops_))),
          1)),
      piston_area_(options.rig.A()),
      design_slope_(options.design_leak * std::sqrt(options.rig.ps) / options.rig.Kv),
      floor_slope_(options.min_leak * std::sqrt(options.rig.ps) / options.rig.Kv),
      sizing_decay_(std::exp(-options.block_seconds / options.sizing_seconds)),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds)),
      supply_(supply_options(options, hop_seconds)),
      drift_(drift_options(options, floor_slope_)) {
  learned_.reserve(clock_.learn_hops());
  scratch_.reserve(clock_.learn_hops());
  // A kept block holds at least min_rest_hops_ of the learned hops.
  probe_blocks_.reserve(clock_.learn_hops() / min_rest_hops_ + 1);
}

void FlowBalanceDetector::reset() {
  clock_.reset();
  observations_ = 0;
  previous_x_ = kMissing;
  before_ = pending_ = Hop{};
  last_ = Decision{};
  learned_.clear();
  probe_blocks_.clear();
  learned_change_.reset();
  coefficients_.setZero();
  positive_loads_ = negative_loads_ = LoadRange{};
  block_sigma_ = hop_sigma_ = kMissing;
  block_hop_ = block_rest_hops_ = block_unsettled_hops_ = 0;
  block_residual_sum_ = block_leak_term_sum_ = block_load_sum_ = 0.0;
  rest_load_low_ = rest_load_high_ = kMissing;
  excitation_wait_hops_ = 0;
  cannot_learn_ = false;
  last_judged_t_ = kMissing;
  block_reason_ = NotJudgedReason::in_motion;
  weighted_ = since_change_ = change_block_ = SlopeSums{};
  cusum_.reset();
  supply_.reset();
  temperature_seen_ = false;
  drift_.clear();
}

double FlowBalanceDetector::supply_for(const Observation& o, double speed) {
  double reading = kMissing;
  if (!std::isnan(o.ps)) {
    reading = o.ps;
  } else if (options_.estimate_supply && !std::isnan(o.p1) && !std::isnan(o.p2) &&
             std::abs(speed) < options_.rest_speed &&
             std::abs(pending_.speed) < options_.rest_speed) {
    // At rest the valve's lands balance: p1 + p2 = ps + pt (MODEL.md).
    reading = o.p1 + o.p2 - options_.rig.pt;
  }
  supply_.add(o.t, reading, !std::isnan(o.ps));
  return supply_.estimate();
}

// The healthy command at rest. The valve's null leakage needs an opening proportional to the
// leak term load / root (as a cross-piston leak would). A command offset (valve bias) is a
// constant, a dead band (overlap) a constant on each side. Spool noise smears the
// dead band's edge, so with overlap the command is a curved function of the flow needed at small
// loads: a quadratic in the load on each side takes that up. The curvature terms hold their value
// outside the loads seen while learning, so only the physical terms extrapolate.
FlowBalanceDetector::Terms FlowBalanceDetector::healthy_terms(const Hop& hop) const {
  const double side = sign_of(hop.load);
  const LoadRange& range = hop.load > 0.0 ? positive_loads_ : negative_loads_;
  const double centred = std::clamp(hop.load, range.low, range.high) - range.middle;
  const double curvature = centred * centred;
  Terms terms;
  terms << 1.0, side, hop.leak_term, side * hop.leak_term, hop.load > 0.0 ? curvature : 0.0,
      hop.load < 0.0 ? curvature : 0.0;
  return terms;
}

double FlowBalanceDetector::expected_opening(const Hop& hop) const {
  return coefficients_.dot(healthy_terms(hop));
}

FlowBalanceDetector::LoadRange FlowBalanceDetector::learned_range(double side) {
  scratch_.clear();
  for (const auto& rest : learned_) {
    if (rest.load * side > 0.0) scratch_.push_back(rest.load);
  }
  if (scratch_.empty()) return {};
  const auto [low, high] = std::minmax_element(scratch_.begin(), scratch_.end());
  LoadRange range{*low, *high, 0.0};
  const auto middle = scratch_.begin() + static_cast<std::ptrdiff_t>(scratch_.size() / 2);
  std::nth_element(scratch_.begin(), middle, scratch_.end());
  range.middle = *middle;
  return range;
}

double FlowBalanceDetector::robust_hop_sigma() {
  scratch_.clear();
  for (const auto& rest : learned_) {
    scratch_.push_back(std::abs(rest.opening - expected_opening(rest)));
  }
  if (scratch_.empty()) return kMissing;
  const auto middle = scratch_.begin() + static_cast<std::ptrdiff_t>(scratch_.size() / 2);
  std::nth_element(scratch_.begin(), middle, scratch_.end());
  return 1.4826 * *middle;  // a normal sigma from the median absolute residual
}

bool FlowBalanceDetector::on_flow_branch(const Hop& hop) const {
  const double short_of_healthy = (expected_opening(hop) - hop.opening) * sign_of(hop.load);
  return !(short_of_healthy > kOffBranchSigmas * hop_sigma_);
}

FlowBalanceDetector::RestLoads FlowBalanceDetector::rests_on_side(double side) const {
  // A rest: consecutive hops at rest (no hop missing between them) on this side, counted once
  // it lasts a block (a few hops at rest are a move's turning point or the tail of its
  // settling). Its load is its hops' mean: a block mean could span the end of one rest and the
  // start of the next, a load between them that was never held.
  RestLoads rests;
  const auto close_rest = [&](double load_sum, std::size_t hops) {
    if (hops < block_hops_) return;
    const double load = load_sum / static_cast<double>(hops);
    rests.low = rests.count == 0 ? load : std::min(rests.low, load);
    rests.high = rests.count == 0 ? load : std::max(rests.high, load);
    ++rests.count;
  };
  double load_sum = 0.0, previous_t = kMissing;
  std::size_t hops = 0;
  for (const auto& rest : learned_) {
    const bool continues = rest.t - previous_t < 1.5 * hop_seconds_;  // false after NaN
    previous_t = rest.t;
    if (!(rest.load * side > 0.0)) {
      close_rest(load_sum, hops);
      load_sum = 0.0, hops = 0;
      continue;
    }
    if (!continues) {
      close_rest(load_sum, hops);
      load_sum = 0.0, hops = 0;
    }
    load_sum += rest.load;
    ++hops;
  }
  close_rest(load_sum, hops);
  return rests;
}

FlowBalanceDetector::LearnedSides FlowBalanceDetector::excited_enough() {
  // The healthy command has an offset, a slope and a curvature on each side of zero load
  // (healthy_terms), so each side needs rests of its own at loads further apart than
  // rest_load_tolerance: two rests for its offset and slope, three for its curvature. A hold at
  // one load and the first two rests of the steps identify neither side; a fit to them judged
  // the steps that followed by coefficients fitted to noise.
  const double needed = options_.min_rest_loads;
  const double tolerance = options_.rest_load_tolerance / options_.rig.ps;
  const RestLoads positive = rests_on_side(1.0);
  const RestLoads negative = rests_on_side(-1.0);
  const auto identified = [&](const RestLoads& rests) {
    if (needed < 2.0) return static_cast<double>(rests.count) >= needed;
    return rests.count >= 2 && rests.high - rests.low > tolerance;
  };
  LearnedSides sides;
  sides.positive = identified(positive);
  sides.negative = identified(negative);
  const std::size_t count =
      (sides.positive ? positive.count : 0) + (sides.negative ? negative.count : 0);
  if (static_cast<double>(count) < needed || (!sides.positive && !sides.negative)) return {};
  sides.positive_curved = sides.positive && positive.count >= 3;
  sides.negative_curved = sides.negative && negative.count >= 3;
  // A side seen at too few loads is left out of the fit and, by the learned range, not judged.
  std::erase_if(learned_, [&](const RestHop& rest) {
    return rest.load > 0.0 ? !sides.positive : !sides.negative;
  });
  rest_load_low_ = sides.negative ? negative.low : positive.low;
  rest_load_high_ = sides.positive ? positive.high : negative.high;
  return sides;
}

void FlowBalanceDetector::set_judged(Decision& decision, double t) const {
  if (decision.learning) {
    decision.judged = false;
    decision.not_judged_reason = excitation_wait_hops_ > 0 ? NotJudgedReason::waiting_for_excitation
                                                           : NotJudgedReason::learning;
    return;
  }
  if (cannot_learn_ || std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) {
    decision.judged = false;
    decision.not_judged_reason = NotJudgedReason::cannot_learn;
    return;
  }
  decision.judged = t - last_judged_t_ <= options_.judged_memory_seconds;  // false when NaN
  decision.not_judged_reason = decision.judged ? NotJudgedReason::none : block_reason_;
}

void FlowBalanceDetector::finish_learning(const LearnedSides& sides) {
  positive_loads_ = learned_range(1.0);
  negative_loads_ = learned_range(-1.0);
  // A side at two loads has no curvature to fit: a range of one point zeroes its term.
  if (!sides.positive_curved)
    positive_loads_ = {positive_loads_.middle, positive_loads_.middle, positive_loads_.middle};
  if (!sides.negative_curved)
    negative_loads_ = {negative_loads_.middle, negative_loads_.middle, negative_loads_.middle};
  // Two passes: the second fit leaves out the hops far off the first (both directions: all of
  // the learning data is healthy), so that a few dead-band crossings do not bend it.
  LeastSquares<kTerms> fit;
  for (const auto& rest : learned_) fit.add(healthy_terms(rest), rest.opening);
  if (fit.count() < 2 * kTerms) {
    clock_.set_learned();  // block_sigma_ stays missing: this detector cannot judge
    return;
  }
  coefficients_ = fit.solve();
  hop_sigma_ = robust_hop_sigma();
  fit.clear();
  for (const auto& rest : learned_) {
    if (std::abs(rest.opening - expected_opening(rest)) <= kOffBranchSigmas * hop_sigma_) {
      fit.add(healthy_terms(rest), rest.opening);
    }
  }
  if (fit.count() >= 2 * kTerms) coefficients_ = fit.solve();
  hop_sigma_ = robust_hop_sigma();
  // Spread of the per-block mean residual, blocks grouped and hops screened exactly as in
  // detection.
  double sum_sq = 0.0, sum_lag = 0.0, previous_mean = 0.0;
  std::size_t blocks = 0, previous_block = 0;
  bool have_previous = false;
  for (std::size_t i = 0; i < learned_.size();) {
    std::size_t j = i, kept = 0;
    double residual_sum = 0.0, leak_term_sum = 0.0;
    for (; j < learned_.size() && learned_[j].block == learned_[i].block; ++j) {
      if (!on_flow_branch(learned_[j])) continue;
      residual_sum += learned_[j].opening - expected_opening(learned_[j]);
      leak_term_sum += learned_[j].leak_term;
      ++kept;
    }
    if (kept >= min_rest_hops_) {
      const double mean = residual_sum / static_cast<double>(kept);
      drift_.add(learned_[j - 1].t, mean, leak_term_sum / static_cast<double>(kept));
      sum_sq += mean * mean;
      if (have_previous && learned_[i].block == previous_block + 1) sum_lag += mean * previous_mean;
      have_previous = true;
      previous_block = learned_[i].block;
      previous_mean = mean;
      ++blocks;
    }
    i = j;
  }
  if (blocks >= 2) {
    // A hold at rest spans a few blocks that share its operating point, so neighbouring block
    // means are correlated; the CUSUM sums them, so use the AR(1) long-run variance.
    block_sigma_ = cusum_block_sigma(std::sqrt(sum_sq / static_cast<double>(blocks - 1)), blocks,
                                     lag_one_correlation(sum_lag, sum_sq));
  }
  probe_learned_change();
  clock_.set_learned();
}

// The healthy relation once more, fitted to the reference share of the learning period only
// (the load ranges and curvature terms stay those of the whole period); the residual blocks of
// the whole period against it, screened like the detection's, go to find_slope_step. The
// coefficients the detector keeps are not touched.
void FlowBalanceDetector::probe_learned_change() {
  learned_change_.reset();
  probe_blocks_.clear();
  if (learned_.empty()) return;
  const double start = learned_.front().t;
  const double split = start + kReferenceShare * (learned_.back().t - start);
  LeastSquares<kTerms> fit;
  for (const auto& rest : learned_) {
    if (rest.t <= split) fit.add(healthy_terms(rest), rest.opening);
  }
  if (fit.count() < 2 * kTerms) return;
  const Terms reference = fit.solve();
  scratch_.clear();
  for (const auto& rest : learned_) {
    if (rest.t <= split)
      scratch_.push_back(std::abs(rest.opening - reference.dot(healthy_terms(rest))));
  }
  const auto middle = scratch_.begin() + static_cast<std::ptrdiff_t>(scratch_.size() / 2);
  std::nth_element(scratch_.begin(), middle, scratch_.end());
  const double hop_sigma = 1.4826 * *middle;
  std::size_t reference_blocks = 0;
  for (std::size_t i = 0; i < learned_.size();) {
    std::size_t j = i, kept = 0;
    double residual_sum = 0.0, leak_term_sum = 0.0;
    for (; j < learned_.size() && learned_[j].block == learned_[i].block; ++j) {
      const double residual = learned_[j].opening - reference.dot(healthy_terms(learned_[j]));
      // Off the flow branch (on_flow_branch, against the reference): a leak only ever needs
      // more opening, so leaving these out cannot hide one.
      if (-residual * sign_of(learned_[j].load) > kOffBranchSigmas * hop_sigma) continue;
      residual_sum += residual;
      leak_term_sum += learned_[j].leak_term;
      ++kept;
    }
    if (kept >= min_rest_hops_) {
      const double n = static_cast<double>(kept);
      probe_blocks_.push_back(
          {learned_[i].t, learned_[j - 1].t, residual_sum / n, leak_term_sum / n});
      if (learned_[j - 1].t <= split) reference_blocks = probe_blocks_.size();
    }
    i = j;
  }
  SlopeStepOptions options;
  options.floor_slope = std::max(floor_slope_, design_slope_);
  options.slope_to_coefficient = options_.rig.Kv / std::sqrt(options_.rig.ps);
  options.fitted_terms = kTerms;
  learned_change_ = find_slope_step(probe_blocks_, reference_blocks, options);
}

void FlowBalanceDetector::judge_block(double t, double mean_residual, double mean_leak_term) {
  // Log-likelihood ratio of "residual = design_slope * leak term" against "residual = 0", in units
  // of the block spread. The designed shift is capped at kMaxShift spreads and the residual
  // winsorised at kMaxZ: one odd block (a disturbance the balance does not model) can then
  // add at most kMaxShift * (kMaxZ - kMaxShift / 2), well below the threshold.
  // The null hypothesis is a leak of min_leak (the floor), so the statistic drifts down below
  // it: z is the block's residual beyond the floor's.
  constexpr double kMaxShift = 3.0, kMaxZ = 4.0;
  const double reference =
      follows_drift() ? drift_.reference(t, block_sigma_, false, kMissing) : 0.0;
  const double excess = mean_residual - reference * mean_leak_term;
  const double shift =
      std::clamp(design_slope_ * mean_leak_term / block_sigma_, -kMaxShift, kMaxShift);
  const double floor = floor_slope_ * mean_leak_term / block_sigma_;
  const double z = std::clamp(excess / block_sigma_ - floor, -kMaxZ, kMaxZ);
  const bool was_quiet = cusum_.value() <= 0.0;
  cusum_.add(t, shift * (z - shift / 2.0));
  // Blocks under suspicion stay out of the drift reference, so a leak is never learned as drift.
  if (cusum_.normalised() < 0.5) drift_.add(t, mean_residual, mean_leak_term);

  const double rl = excess * mean_leak_term, ll = mean_leak_term * mean_leak_term;
  weighted_.rl = sizing_decay_ * weighted_.rl + rl;
  weighted_.ll = sizing_decay_ * weighted_.ll + ll;
  weighted_.ll_sq = sizing_decay_ * sizing_decay_ * weighted_.ll_sq + ll;
  if (was_quiet) since_change_ = change_block_ = SlopeSums{};
  if (cusum_.value() > 0.0) {
    SlopeSums& into = was_quiet ? change_block_ : since_change_;
    into.rl += rl;
    into.ll += ll;
    into.ll_sq += ll;
  }
}

Decision FlowBalanceDetector::update(const Observation& o) {
  // Load, root factor and leak term are scaled by the configured supply (a constant), so the
  // learned coefficients keep their meaning when the actual supply moves; the orifice law
  // itself is evaluated at the actual supply.
  const double ps_ref = options_.rig.ps;
  Hop hop;
  hop.t = o.t;
  hop.speed = (o.x - previous_x_) / hop_seconds_;
  previous_x_ = o.x;
  hop.supply = supply_for(o, hop.speed);
  if (!std::isnan(o.temp)) temperature_seen_ = true;
  const bool temperature_ok = !temperature_seen_ || !std::isnan(o.temp);
  const bool supply_settled = supply_.settled(o.t);
  if (!supply_settled && clock_.learned()) ++block_unsettled_hops_;
  hop.usable = !std::isnan(o.u) && !std::isnan(o.p1) && !std::isnan(o.p2) &&
               !std::isnan(hop.speed) && temperature_ok && supply_settled &&
               std::abs(o.u) < 0.5 * options_.rig.u_max;
  if (hop.usable) {
    // Judged in the command's own units (fractions of full spool travel), on the side the
    // load makes the valve open to at rest (it feeds the leaks out of the loaded chamber): so
    // a command offset or a dead band is a constant whatever the command's sign, where the
    // orifice law read through the measured command would switch sides at the wrong place.
    // Load in units of ps, root factor in units of sqrt(ps).
    sim::Parameters rig = options_.rig;
    rig.ps = hop.supply;
    hop.load = (o.p1 - o.p2) / ps_ref;
    const double full_open = std::copysign(rig.u_max, hop.load);
    const double root = std::abs(load_flow_per_kv(rig, full_open, o.p1, o.p2)) / std::sqrt(ps_ref);
    hop.usable = hop.usable && root > kMinRoot;
    hop.opening = o.u / rig.u_max - piston_area_ * hop.speed / (rig.Kv * std::sqrt(ps_ref) * root);
    // Laminar leaks follow the viscosity: scaled to 40 degC, the learned null leakage and any
    // new leak are constants of the rig.
    hop.viscosity_ratio = std::isnan(o.temp) ? kMissing : options_.oil.ratio(o.temp);
    hop.leak_term = hop.load / root * (std::isnan(o.temp) ? 1.0 : hop.viscosity_ratio);
    hop.root = root;
  }
  auto still = [&](const Hop& h) { return h.usable && std::abs(h.speed) < options_.rest_speed; };
  const bool pending_at_rest = still(before_) && still(pending_) && still(hop);
  const Hop judged = pending_;
  before_ = pending_;
  pending_ = hop;
  if (++observations_ > 1) accept(judged, pending_at_rest);
  return last_;
}

void FlowBalanceDetector::accept(const Hop& hop, bool at_rest) {
  const double ps = options_.rig.ps;  // the scale of the slope (see update())
  Decision decision;
  const bool past_settling = clock_.count_hop();
  if (!clock_.learned()) decision.learning_hops_left = clock_.hops_left();
  if (!past_settling) {
    last_ = decision;
    return;
  }
  if (!clock_.learned()) {
    if (at_rest) learned_.push_back({hop, clock_.learning_hop() / block_hops_});
    if (clock_.period_over()) {
      const std::size_t max_wait_hops = static_cast<std::size_t>(
          std::lround(options_.max_excitation_wait_seconds / hop_seconds_));
      if (const LearnedSides sides = excited_enough(); sides.positive || sides.negative) {
        finish_learning(sides);
        block_reason_ = NotJudgedReason::in_motion;
      } else if (excitation_wait_hops_ >= max_wait_hops) {
        // Learning from these data would extrapolate the healthy command from one load.
        cannot_learn_ = true;
        learned_.clear();
        clock_.set_learned();
      } else {
        excitation_wait_hops_ += clock_.learn_hops();
        learned_.clear();
        clock_.restart_period();
      }
    }
    if (!clock_.learned()) decision.learning_hops_left = clock_.hops_left();
    set_judged(decision, hop.t);
    last_ = decision;
    return;
  }
  decision.learning = false;
  if (cannot_learn_ || std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) {
    set_judged(decision, hop.t);
    last_ = decision;
    return;
  }
  if (at_rest && on_flow_branch(hop)) {
    block_residual_sum_ += hop.opening - expected_opening(hop);
    block_leak_term_sum_ += hop.leak_term;
    block_load_sum_ += hop.load;
    ++block_rest_hops_;
  }
  if (++block_hop_ >= block_hops_) {
    if (block_rest_hops_ >= min_rest_hops_) {
      const double n = static_cast<double>(block_rest_hops_);
      const double load = block_load_sum_ / n;
      const double margin = options_.rest_load_tolerance / options_.rig.ps;
      // NaN bounds (an older state) compare false: no limit.
      if (options_.limit_to_learned &&
          (load < rest_load_low_ - margin || load > rest_load_high_ + margin)) {
        block_reason_ = NotJudgedReason::outside_learned_loads;
      } else {
        judge_block(hop.t, block_residual_sum_ / n, block_leak_term_sum_ / n);
        if (std::abs(load) * options_.rig.ps < options_.no_load_pressure) {
          block_reason_ = NotJudgedReason::no_load;
        } else {
          last_judged_t_ = hop.t;
        }
      }
    } else {
      block_reason_ =
          block_unsettled_hops_ > 0 ? NotJudgedReason::supply_settling : NotJudgedReason::in_motion;
    }
    block_hop_ = block_rest_hops_ = block_unsettled_hops_ = 0;
    block_residual_sum_ = block_leak_term_sum_ = block_load_sum_ = 0.0;
  }
  set_judged(decision, hop.t);
  decision.score = cusum_.normalised();
  decision.viscosity_ratio = hop.viscosity_ratio;
  const SlopeSums& sums = cusum_.value() <= 0.0    ? weighted_
                          : since_change_.ll > 0.0 ? since_change_
                          : change_block_.ll > 0.0 ? change_block_
                                                   : weighted_;
  if (sums.ll > 0.0) {
    const double to_leak = options_.rig.Kv / std::sqrt(ps);
    const double slope = sums.rl / sums.ll;
    const double slope_se = block_sigma_ * std::sqrt(sums.ll_sq) / sums.ll;
    decision.leak_coefficient = slope * to_leak;
    decision.leak_coefficient_ci =
        1.96 * slope_se * to_leak +
        options_.valve_coefficient_uncertainty * std::abs(decision.leak_coefficient);
  }
  last_ = decision;
}

}  // namespace leakmon::detect

namespace leakmon::detect {

namespace {

// The state's names of the healthy model's terms (healthy_terms()).
constexpr std::array<std::string_view, 6> kTermNames = {
    "constant", "side", "leak_term", "side_leak_term", "curvature_positive", "curvature_negative"};

void put_hop(DetectorState& state, std::string_view prefix, const auto& hop, const auto& fields) {
  for (const auto& field : fields) state.put(state_key(prefix, field.name), field.get(hop));
}

void get_hop(const DetectorState& state, std::string_view prefix, auto& hop, const auto& fields) {
  for (const auto& field : fields) field.set(hop, state.get(state_key(prefix, field.name)));
}

}  // namespace

DetectorState FlowBalanceDetector::export_state() const {
  DetectorState state(std::string(name()), kStateVersion);
  clock_.save(state, "learning");
  state.put_count("observations", observations_);
  state.put("previous_x", previous_x_);
  put_hop(state, "before", before_, hop_fields<Hop>());
  put_hop(state, "pending", pending_, hop_fields<Hop>());
  put_records(state, "learned", std::span<const RestHop>(learned_), rest_hop_fields());
  for (const auto& [key, range] : {std::pair{"positive_loads", &positive_loads_},
                                   std::pair{"negative_loads", &negative_loads_}}) {
    state.put(state_key(key, "low"), range->low);
    state.put(state_key(key, "high"), range->high);
    state.put(state_key(key, "middle"), range->middle);
  }
  for (int i = 0; i < kTerms; ++i) {
    state.put(state_key("coefficient", kTermNames[static_cast<std::size_t>(i)]), coefficients_[i]);
  }
  state.put("hop_sigma", hop_sigma_);
  state.put("block_sigma", block_sigma_);
  state.put_count("block.hops", block_hop_);
  state.put_count("block.rest_hops", block_rest_hops_);
  state.put("block.residual_sum", block_residual_sum_);
  state.put("block.leak_term_sum", block_leak_term_sum_);
  state.put("block.load_sum", block_load_sum_);
  state.put_count("block.unsettled_hops", block_unsettled_hops_);
  state.put("rest_loads.low", rest_load_low_);
  state.put("rest_loads.high", rest_load_high_);
  state.put_count("excitation.wait_hops", excitation_wait_hops_);
  state.put("excitation.cannot_learn", cannot_learn_ ? 1.0 : 0.0);
  state.put("judging.last_judged_t", last_judged_t_);
  state.put("judging.reason", static_cast<double>(block_reason_));
  for (const auto& [key, sums] :
       {std::pair{"sizing.weighted", &weighted_}, std::pair{"sizing.since_change", &since_change_},
        std::pair{"sizing.change_block", &change_block_}}) {
    state.put(state_key(key, "rl"), sums->rl);
    state.put(state_key(key, "ll"), sums->ll);
    state.put(state_key(key, "ll_sq"), sums->ll_sq);
  }
  cusum_.save(state, "cusum");
  state.put("last.score", last_.score);
  state.put("last.learning", last_.learning ? 1.0 : 0.0);
  state.put("last.baseline", last_.baseline);
  state.put("last.index", last_.index);
  state.put("last.leak_coefficient", last_.leak_coefficient);
  state.put("last.leak_coefficient_ci", last_.leak_coefficient_ci);
  state.put("last.viscosity_ratio", last_.viscosity_ratio);
  supply_.save(state, "supply");
  state.put("temperature_seen", temperature_seen_ ? 1.0 : 0.0);
  drift_.save(state, "drift");
  return state;
}

void FlowBalanceDetector::import_state(const DetectorState& saved) {
  import_detector_state(*this, saved, kStateVersion, [this](const DetectorState& state) {
    clock_.restore(state, "learning");
    observations_ = state.get_count("observations");
    previous_x_ = state.get("previous_x");
    get_hop(state, "before", before_, hop_fields<Hop>());
    get_hop(state, "pending", pending_, hop_fields<Hop>());
    const std::size_t learned = record_count(state, "learned", rest_hop_fields());
    if (learned > learned_.capacity()) {
      throw StateError("learned hops do not fit this configuration");
    }
    learned_.resize(learned);  // within the reserved capacity
    get_records(state, "learned", rest_hop_fields(), std::span<RestHop>(learned_));
    for (const auto& [key, range] : {std::pair{"positive_loads", &positive_loads_},
                                     std::pair{"negative_loads", &negative_loads_}}) {
      range->low = state.get(state_key(key, "low"));
      range->high = state.get(state_key(key, "high"));
      range->middle = state.get(state_key(key, "middle"));
    }
    for (int i = 0; i < kTerms; ++i) {
      coefficients_[i] =
          state.get(state_key("coefficient", kTermNames[static_cast<std::size_t>(i)]));
    }
    hop_sigma_ = state.get("hop_sigma");
    block_sigma_ = state.get("block_sigma");
    block_hop_ = state.get_count("block.hops");
    block_rest_hops_ = state.get_count("block.rest_hops");
    if (block_hop_ >= block_hops_ || block_rest_hops_ > block_hop_) {
      throw StateError("block position out of range");
    }
    block_residual_sum_ = state.get("block.residual_sum");
    block_leak_term_sum_ = state.get("block.leak_term_sum");
    block_load_sum_ = state.get("block.load_sum");
    block_unsettled_hops_ = state.get_count("block.unsettled_hops");
    rest_load_low_ = state.get("rest_loads.low");
    rest_load_high_ = state.get("rest_loads.high");
    excitation_wait_hops_ = state.get_count("excitation.wait_hops");
    cannot_learn_ = state.get("excitation.cannot_learn") != 0.0;
    last_judged_t_ = state.get("judging.last_judged_t");
    const double reason = state.get("judging.reason");
    if (!(reason >= 0.0 && reason < static_cast<double>(kNotJudgedReasonNames.size()))) {
      throw StateError("judging.reason out of range");
    }
    block_reason_ = static_cast<NotJudgedReason>(static_cast<int>(reason));
    for (const auto& [key, sums] : {std::pair{"sizing.weighted", &weighted_},
                                    std::pair{"sizing.since_change", &since_change_},
                                    std::pair{"sizing.change_block", &change_block_}}) {
      *sums = SlopeSums{state.get(state_key(key, "rl")), state.get(state_key(key, "ll")),
                        state.get(state_key(key, "ll_sq"))};
    }
    cusum_.restore(state, "cusum");
    last_.score = state.get("last.score");
    last_.learning = state.get("last.learning") != 0.0;
    last_.baseline = state.get("last.baseline");
    last_.index = state.get("last.index");
    last_.leak_coefficient = state.get("last.leak_coefficient");
    last_.leak_coefficient_ci = state.get("last.leak_coefficient_ci");
    last_.viscosity_ratio = state.get("last.viscosity_ratio");
    supply_.restore(state, "supply");
    temperature_seen_ = state.get("temperature_seen") != 0.0;
    drift_.restore(state, "drift");
  });
}

// The drift reference and the supply transient are on the old source clock; the hops before the
// gap are not neighbours of the next ones.
void FlowBalanceDetector::resume_after_gap() {
  drift_.clear();
  last_judged_t_ = kMissing;  // on the old source clock
  supply_.resume_after_gap();
  previous_x_ = kMissing;
  before_ = pending_ = Hop{};
}

}  // namespace leakmon::detect
