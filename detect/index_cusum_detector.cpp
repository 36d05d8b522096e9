#include "detect/index_cusum_detector.hpp"

#include <algorithm>
#include <cmath>

#include "detect/least_squares.hpp"

namespace leakmon::detect {

namespace {

// The learned spread comes from ~100 blocks; inflate it to its one-sided 95 % upper confidence
// bound so that a lucky learning period does not set a hair trigger.
double upper_sigma_bound(double sigma, std::size_t blocks) {
  if (blocks < 2) return sigma;
  return sigma * (1.0 + 1.645 / std::sqrt(2.0 * static_cast<double>(blocks - 1)));
}

// Load activity below this (1e-3 of supply per hop) counts as "still": keeps the log finite.
constexpr double kActivityFloor = 1e-3;

}  // namespace

IndexCusumDetector::IndexCusumDetector(const IndexCusumOptions& options, double hop_seconds)
    : options_(options),
      settle_hops_(options.learning.settle_hops(hop_seconds)),
      learn_hops_(std::max<std::size_t>(options.learning.learn_hops(hop_seconds), 1)),
      block_hops_(std::max<std::size_t>(
          static_cast<std::size_t>(std::lround(options.block_seconds / hop_seconds)), 1)),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds)) {
  learned_.reserve(learn_hops_ / block_hops_ + 1);
}

void IndexCusumDetector::reset() {
  hops_seen_ = 0;
  learned_.clear();
  learned_model_ = false;
  block_sigma_ = kMissing;
  block_hop_ = block_valid_ = 0;
  sum_log_index_ = sum_load_ = sum_load_squared_ = sum_activity_ = 0.0;
  previous_load_ = last_expected_ = kMissing;
  cusum_.reset();
}

double IndexCusumDetector::log_index_of(const Observation& o) const {
  double sum = 0.0;
  int used = 0;
  for (const auto& [use, index] :
       {std::pair{options_.use_p1, o.index_p1}, std::pair{options_.use_p2, o.index_p2}}) {
    if (!use) continue;
    if (!(index > 0.0)) return kMissing;  // a configured chamber with a gap: judge nothing
    sum += std::log(index);
    ++used;
  }
  return used > 0 ? sum / used : kMissing;
}

// Load pressure p1 - p2 over supply; with one chamber, that chamber's departure from mid-supply
// (the two chambers mirror each other around it at rest).
double IndexCusumDetector::load_of(const Observation& o) const {
  const double ps = options_.rig.ps;
  if (!std::isnan(o.p1) && !std::isnan(o.p2)) return (o.p1 - o.p2) / ps;
  if (!std::isnan(o.p1)) return (2.0 * o.p1 - ps) / ps;
  if (!std::isnan(o.p2)) return (ps - 2.0 * o.p2) / ps;
  return kMissing;
}

double IndexCusumDetector::expected_log_index(const Block& b) const {
  return coefficients_[0] + coefficients_[1] * b.load + coefficients_[2] * b.load_squared +
         coefficients_[3] * b.log_activity;
}

// Adds one hop; true when a block completed with enough valid hops (then `completed` holds it).
bool IndexCusumDetector::add_to_block(double log_index, double load, Block& completed) {
  const double activity = std::abs(load - previous_load_);
  previous_load_ = load;
  if (!std::isnan(log_index) && !std::isnan(activity)) {
    sum_log_index_ += log_index;
    sum_load_ += load;
    sum_load_squared_ += load * load;
    sum_activity_ += activity;
    ++block_valid_;
  }
  if (++block_hop_ < block_hops_) return false;
  const bool enough = 2 * block_valid_ >= block_hops_;
  if (enough) {
    const double n = static_cast<double>(block_valid_);
    completed = {sum_log_index_ / n, sum_load_ / n, sum_load_squared_ / n,
                 std::log(sum_activity_ / n + kActivityFloor)};
  }
  block_hop_ = block_valid_ = 0;
  sum_log_index_ = sum_load_ = sum_load_squared_ = sum_activity_ = 0.0;
  return enough;
}

void IndexCusumDetector::finish_learning() {
  learned_model_ = true;
  if (learned_.size() < 2 * kRegressors) return;  // too little data: never judges
  LeastSquares<kRegressors> fit;
  for (const auto& b : learned_) {
    fit.add(Eigen::Vector4d(1.0, b.load, b.load_squared, b.log_activity), b.log_index);
  }
  const Eigen::Vector4d beta = fit.solve();
  for (int i = 0; i < kRegressors; ++i) coefficients_[i] = beta[i];
  double sum_sq = 0.0, sum_lag = 0.0, previous = kMissing;
  for (const auto& b : learned_) {
    const double r = b.log_index - expected_log_index(b);
    sum_sq += r * r;
    if (!std::isnan(previous)) sum_lag += r * previous;
    previous = r;
  }
  const auto n = learned_.size();
  const double sigma = std::sqrt(sum_sq / static_cast<double>(n - kRegressors));
  // AR(1) long-run variance (1 + rho) / (1 - rho): the CUSUM sums correlated blocks.
  const double rho = std::clamp(sum_lag / sum_sq, 0.0, 0.8);
  block_sigma_ = upper_sigma_bound(sigma, n) * std::sqrt((1.0 + rho) / (1.0 - rho));
}

Decision IndexCusumDetector::update(const Observation& observation) {
  Decision decision;
  const double log_index = log_index_of(observation);
  decision.index = std::isnan(log_index) ? kMissing : std::exp(log_index);
  ++hops_seen_;
  if (hops_seen_ <= settle_hops_) return decision;

  Block block{};
  const bool completed = add_to_block(log_index, load_of(observation), block);
  if (!learned_model_) {
    if (completed) learned_.push_back(block);  // capacity reserved: never reallocates
    if (hops_seen_ - settle_hops_ >= learn_hops_) finish_learning();
    return decision;
  }
  decision.learning = false;
  if (std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) return decision;
  if (completed) {
    last_expected_ = expected_log_index(block);
    // Log-likelihood ratio of "mean residual is log(1 - design_drop)" against "0", per block.
    const double shift = std::log1p(-options_.design_drop) / block_sigma_;  // negative
    const double z = (block.log_index - last_expected_) / block_sigma_;
    cusum_.add(shift * (z - shift / 2.0));
  }
  decision.baseline = std::isnan(last_expected_) ? kMissing : std::exp(last_expected_);
  decision.score = cusum_.normalised();
  return decision;
}

}  // namespace leakmon::detect
