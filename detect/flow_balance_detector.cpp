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
      design_slope_(options.design_leak * std::sqrt(options.valve.supply_pressure) /
                    options.valve_coefficient),
      sizing_decay_(std::exp(-options.block_seconds / options.sizing_seconds)),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds)) {
  learned_.reserve(learn_hops_);
}

void FlowBalanceDetector::reset() {
  hops_seen_ = observations_ = 0;
  previous_x_ = kMissing;
  before_ = pending_ = Hop{};
  last_ = Decision{};
  learned_.clear();
  learned_model_ = false;
  block_sigma_ = kMissing;
  block_hop_ = block_rest_hops_ = 0;
  block_residual_sum_ = block_load_sum_ = 0.0;
  weighted_ = since_change_ = SlopeSums{};
  cusum_.reset();
}

double FlowBalanceDetector::expected_flow(double load) const {
  return coefficients_[0] + coefficients_[1] * load + coefficients_[2] * sign_of(load);
}

void FlowBalanceDetector::finish_learning() {
  LeastSquares<3> fit;
  for (const auto& hop : learned_) {
    fit.add(Eigen::Vector3d(1.0, hop.load, sign_of(hop.load)), hop.flow);
  }
  if (fit.count() >= 3) {
    const Eigen::Vector3d beta = fit.solve();
    for (int i = 0; i < 3; ++i) coefficients_[i] = beta[i];
  }
  // Spread of the per-block mean residual, blocks grouped exactly as in detection.
  double sum_sq = 0.0;
  std::size_t blocks = 0;
  for (std::size_t i = 0; i < learned_.size();) {
    std::size_t j = i;
    double residual_sum = 0.0;
    while (j < learned_.size() && learned_[j].block == learned_[i].block) {
      residual_sum += learned_[j].flow - expected_flow(learned_[j].load);
      ++j;
    }
    if (j - i >= min_rest_hops_) {
      const double mean = residual_sum / static_cast<double>(j - i);
      sum_sq += mean * mean;
      ++blocks;
    }
    i = j;
  }
  block_sigma_ =
      blocks >= 2 ? upper_sigma_bound(std::sqrt(sum_sq / static_cast<double>(blocks - 1)), blocks)
                  : kMissing;
  learned_model_ = true;
}

void FlowBalanceDetector::judge_block(double mean_residual, double mean_load) {
  // Log-likelihood ratio of "residual = design_slope * load" against "residual = 0", in units
  // of the block spread. The designed shift is capped at kMaxShift spreads and the residual
  // winsorised at kMaxZ: one odd block (a disturbance the balance does not model) can then
  // add at most kMaxShift * (kMaxZ - kMaxShift / 2), well below the threshold.
  constexpr double kMaxShift = 3.0, kMaxZ = 4.0;
  const double shift = std::clamp(design_slope_ * mean_load / block_sigma_, -kMaxShift, kMaxShift);
  const double z = std::clamp(mean_residual / block_sigma_, -kMaxZ, kMaxZ);
  const bool was_quiet = cusum_.value() <= 0.0;
  cusum_.add(shift * (z - shift / 2.0));

  const double rl = mean_residual * mean_load, ll = mean_load * mean_load;
  weighted_.rl = sizing_decay_ * weighted_.rl + rl;
  weighted_.ll = sizing_decay_ * weighted_.ll + ll;
  weighted_.ll_sq = sizing_decay_ * sizing_decay_ * weighted_.ll_sq + ll;
  if (was_quiet) since_change_ = SlopeSums{};
  if (cusum_.value() > 0.0) {
    since_change_.rl += rl;
    since_change_.ll += ll;
    since_change_.ll_sq += ll;
  }
}

Decision FlowBalanceDetector::update(const Observation& o) {
  const double ps = options_.valve.supply_pressure;
  Hop hop;
  hop.speed = (o.x - previous_x_) / hop_seconds_;
  previous_x_ = o.x;
  hop.usable = !std::isnan(o.u) && !std::isnan(o.p1) && !std::isnan(o.p2) &&
               !std::isnan(hop.speed) && std::abs(o.u) < 0.5 * options_.valve.command_full_scale;
  if (hop.usable) {
    // Normalised so both are O(0.01..1): flow in units of Kv sqrt(ps), load in units of ps.
    hop.flow = load_flow_per_kv(options_.valve, o.u, o.p1, o.p2) / std::sqrt(ps) -
               options_.piston_area * hop.speed / (options_.valve_coefficient * std::sqrt(ps));
    hop.load = (o.p1 - o.p2) / ps;
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
  const double ps = options_.valve.supply_pressure;
  Decision decision;
  ++hops_seen_;
  if (hops_seen_ <= settle_hops_) {
    last_ = decision;
    return;
  }
  const std::size_t hop_in_phase = hops_seen_ - settle_hops_ - 1;
  if (!learned_model_) {
    if (at_rest) learned_.push_back({hop.flow, hop.load, hop_in_phase / block_hops_});
    if (hop_in_phase + 1 >= learn_hops_) finish_learning();
    last_ = decision;
    return;
  }
  decision.learning = false;
  if (std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) {
    last_ = decision;
    return;
  }
  if (at_rest) {
    block_residual_sum_ += hop.flow - expected_flow(hop.load);
    block_load_sum_ += hop.load;
    ++block_rest_hops_;
  }
  if (++block_hop_ >= block_hops_) {
    if (block_rest_hops_ >= min_rest_hops_) {
      const double n = static_cast<double>(block_rest_hops_);
      judge_block(block_residual_sum_ / n, block_load_sum_ / n);
    }
    block_hop_ = block_rest_hops_ = 0;
    block_residual_sum_ = block_load_sum_ = 0.0;
  }
  decision.score = cusum_.normalised();
  const SlopeSums& sums =
      cusum_.value() > 0.0 && since_change_.ll > 0.0 ? since_change_ : weighted_;
  if (sums.ll > 0.0) {
    const double to_leak = options_.valve_coefficient / std::sqrt(ps);
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
