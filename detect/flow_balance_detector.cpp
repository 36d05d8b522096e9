#include "detect/flow_balance_detector.hpp"

#include <algorithm>
#include <cmath>

#include "detect/least_squares.hpp"

namespace leakmon::detect {

namespace {

double sign_of(double value) { return value > 0.0 ? 1.0 : (value < 0.0 ? -1.0 : 0.0); }

double upper_sigma_bound(double sigma, std::size_t blocks) {
  if (blocks < 2) return sigma;
  return sigma * (1.0 + 1.645 / std::sqrt(2.0 * static_cast<double>(blocks - 1)));
}

}  // namespace

FlowBalanceDetector::FlowBalanceDetector(const FlowBalanceOptions& options, double hop_seconds)
    : options_(options),
      hop_seconds_(hop_seconds),
      settle_hops_(options.learning.settle_hops(hop_seconds)),
      learn_hops_(std::max<std::size_t>(options.learning.learn_hops(hop_seconds), 1)),
      block_hops_(std::max<std::size_t>(
          static_cast<std::size_t>(std::lround(options.block_seconds / hop_seconds)), 1)),
      min_rest_hops_(std::max<std::size_t>(
          static_cast<std::size_t>(
              std::ceil(options.min_rest_fraction * static_cast<double>(block_hops_))),
          1)),
      piston_area_(options.rig.A()),
      design_slope_(options.design_leak * std::sqrt(options.rig.ps) / options.rig.Kv),
      sizing_decay_(std::exp(-options.block_seconds / options.sizing_seconds)),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds)) {
  learned_.reserve(learn_hops_);
  scratch_.reserve(learn_hops_);
}

void FlowBalanceDetector::reset() {
  hops_seen_ = observations_ = 0;
  previous_x_ = kMissing;
  before_ = pending_ = Hop{};
  last_ = Decision{};
  learned_.clear();
  learned_model_ = false;
  coefficients_.setZero();
  positive_loads_ = negative_loads_ = LoadRange{};
  block_sigma_ = hop_sigma_ = kMissing;
  block_hop_ = block_rest_hops_ = 0;
  block_residual_sum_ = block_leak_term_sum_ = 0.0;
  weighted_ = since_change_ = change_block_ = SlopeSums{};
  cusum_.reset();
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
    if (rest.hop.load * side > 0.0) scratch_.push_back(rest.hop.load);
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
    scratch_.push_back(std::abs(rest.hop.opening - expected_opening(rest.hop)));
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

void FlowBalanceDetector::finish_learning() {
  positive_loads_ = learned_range(1.0);
  negative_loads_ = learned_range(-1.0);
  // Two passes: the second fit leaves out the hops far off the first (both directions: all of
  // the learning data is healthy), so that a few dead-band crossings do not bend it.
  LeastSquares<kTerms> fit;
  for (const auto& rest : learned_) fit.add(healthy_terms(rest.hop), rest.hop.opening);
  if (fit.count() < 2 * kTerms) {
    learned_model_ = true;  // block_sigma_ stays missing: this detector cannot judge
    return;
  }
  coefficients_ = fit.solve();
  hop_sigma_ = robust_hop_sigma();
  fit.clear();
  for (const auto& rest : learned_) {
    if (std::abs(rest.hop.opening - expected_opening(rest.hop)) <= kOffBranchSigmas * hop_sigma_) {
      fit.add(healthy_terms(rest.hop), rest.hop.opening);
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
    double residual_sum = 0.0;
    for (; j < learned_.size() && learned_[j].block == learned_[i].block; ++j) {
      if (!on_flow_branch(learned_[j].hop)) continue;
      residual_sum += learned_[j].hop.opening - expected_opening(learned_[j].hop);
      ++kept;
    }
    if (kept >= min_rest_hops_) {
      const double mean = residual_sum / static_cast<double>(kept);
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
    const double rho = std::clamp(sum_lag / sum_sq, 0.0, 0.8);
    block_sigma_ = upper_sigma_bound(std::sqrt(sum_sq / static_cast<double>(blocks - 1)), blocks) *
                   std::sqrt((1.0 + rho) / (1.0 - rho));
  }
  learned_model_ = true;
}

void FlowBalanceDetector::judge_block(double mean_residual, double mean_leak_term) {
  // Log-likelihood ratio of "residual = design_slope * leak term" against "residual = 0", in units
  // of the block spread. The designed shift is capped at kMaxShift spreads and the residual
  // winsorised at kMaxZ: one odd block (a disturbance the balance does not model) can then
  // add at most kMaxShift * (kMaxZ - kMaxShift / 2), well below the threshold.
  constexpr double kMaxShift = 3.0, kMaxZ = 4.0;
  const double shift =
      std::clamp(design_slope_ * mean_leak_term / block_sigma_, -kMaxShift, kMaxShift);
  const double z = std::clamp(mean_residual / block_sigma_, -kMaxZ, kMaxZ);
  const bool was_quiet = cusum_.value() <= 0.0;
  cusum_.add(shift * (z - shift / 2.0));

  const double rl = mean_residual * mean_leak_term, ll = mean_leak_term * mean_leak_term;
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
  const double ps = options_.rig.ps;
  Hop hop;
  hop.speed = (o.x - previous_x_) / hop_seconds_;
  previous_x_ = o.x;
  hop.usable = !std::isnan(o.u) && !std::isnan(o.p1) && !std::isnan(o.p2) &&
               !std::isnan(hop.speed) && std::abs(o.u) < 0.5 * options_.rig.u_max;
  if (hop.usable) {
    // Judged in the command's own units (fractions of full spool travel), on the side the
    // load makes the valve open to at rest (it feeds the leaks out of the loaded chamber): so
    // a command offset or a dead band is a constant whatever the command's sign, where the
    // orifice law read through the measured command would switch sides at the wrong place.
    // Load in units of ps, root factor in units of sqrt(ps).
    hop.load = (o.p1 - o.p2) / ps;
    const double full_open = std::copysign(options_.rig.u_max, hop.load);
    const double root =
        std::abs(load_flow_per_kv(options_.rig, full_open, o.p1, o.p2)) / std::sqrt(ps);
    hop.usable = hop.usable && root > kMinRoot;
    hop.opening = o.u / options_.rig.u_max -
                  piston_area_ * hop.speed / (options_.rig.Kv * std::sqrt(ps) * root);
    hop.leak_term = hop.load / root;
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
  const double ps = options_.rig.ps;
  Decision decision;
  ++hops_seen_;
  if (hops_seen_ <= settle_hops_) {
    last_ = decision;
    return;
  }
  const std::size_t hop_in_phase = hops_seen_ - settle_hops_ - 1;
  if (!learned_model_) {
    if (at_rest) learned_.push_back({hop, hop_in_phase / block_hops_});
    if (hop_in_phase + 1 >= learn_hops_) finish_learning();
    last_ = decision;
    return;
  }
  decision.learning = false;
  if (std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) {
    last_ = decision;
    return;
  }
  if (at_rest && on_flow_branch(hop)) {
    block_residual_sum_ += hop.opening - expected_opening(hop);
    block_leak_term_sum_ += hop.leak_term;
    ++block_rest_hops_;
  }
  if (++block_hop_ >= block_hops_) {
    if (block_rest_hops_ >= min_rest_hops_) {
      const double n = static_cast<double>(block_rest_hops_);
      judge_block(block_residual_sum_ / n, block_leak_term_sum_ / n);
    }
    block_hop_ = block_rest_hops_ = 0;
    block_residual_sum_ = block_leak_term_sum_ = 0.0;
  }
  decision.score = cusum_.normalised();
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
