#include "detect/learned_change.hpp"

#include <algorithm>
#include <cmath>

#include "detect/cusum.hpp"
#include "detect/learning_schedule.hpp"

namespace leakmon::detect {

std::optional<LearnedChange> find_slope_step(std::span<const ResidualBlock> blocks,
                                             std::size_t reference_blocks,
                                             const SlopeStepOptions& options) {
  // A reference of hardly more blocks than the fitted terms is fitted almost exactly, whatever
  // the noise: a 12 s learning period gave 6 blocks for the flow balance's 6 terms and a healthy
  // rig's step came out at 70 standard errors.
  const std::size_t fitted = std::max<std::size_t>(options.fitted_terms, 1);
  if (reference_blocks < fitted + kMinReferenceDof ||
      blocks.size() < reference_blocks + options.min_blocks_after) {
    return std::nullopt;
  }
  // The spread of a block mean around the reference fit, as the AR(1) long-run one: the blocks
  // of one hold share its operating point.
  double sum_sq = 0.0, sum_lag = 0.0;
  for (std::size_t i = 0; i < reference_blocks; ++i) {
    sum_sq += blocks[i].residual * blocks[i].residual;
    if (i > 0) sum_lag += blocks[i].residual * blocks[i - 1].residual;
  }
  if (!(sum_sq > 0.0)) return std::nullopt;
  const std::size_t dof = reference_blocks - fitted;
  const double sigma = cusum_block_sigma(std::sqrt(sum_sq / static_cast<double>(dof)), dof + 1,
                                         lag_one_correlation(sum_lag, sum_sq));
  // The added slope after each candidate block k, by least squares over the blocks from k on;
  // scanned backwards so each candidate costs one step.
  std::optional<LearnedChange> best;
  double residual_term = 0.0, term_sq = 0.0;
  for (std::size_t k = blocks.size(); k-- > reference_blocks;) {
    residual_term += blocks[k].residual * blocks[k].leak_term;
    term_sq += blocks[k].leak_term * blocks[k].leak_term;
    if (blocks.size() - k < options.min_blocks_after || !(term_sq > 0.0)) continue;
    const double slope = residual_term / term_sq;
    const double z = slope * std::sqrt(term_sq) / sigma;
    if (best && z <= best->z) continue;
    best = LearnedChange{
        blocks[k].t_first, options.feature, "u", slope * options.slope_to_coefficient, 0.0, z};
  }
  if (!best || best->z < options.min_z ||
      best->size < options.floor_slope * options.slope_to_coefficient) {
    return std::nullopt;
  }
  return best;
}

IndexStepProbe::IndexStepProbe(std::string_view channel, double learning_seconds,
                               double hop_seconds, const Options& options)
    : channel_(channel),
      options_(options),
      block_hops_(hops_in(options.block_seconds, hop_seconds)) {
  const double blocks =
      std::isfinite(learning_seconds) ? learning_seconds / options.block_seconds : 0.0;
  blocks_.reserve(static_cast<std::size_t>(std::max(0.0, blocks)) + 4);
  scratch_.reserve(blocks_.capacity());
}

void IndexStepProbe::clear() {
  blocks_.clear();
  sum_ = first_t_ = last_t_ = 0.0;
  count_ = hops_in_block_ = 0;
}

void IndexStepProbe::add(double t, double index) {
  if (hops_in_block_ == 0) first_t_ = t;
  ++hops_in_block_;
  if (std::isfinite(index)) {
    sum_ += index;
    ++count_;
  }
  last_t_ = t;
  if (hops_in_block_ >= block_hops_) close_block();
}

void IndexStepProbe::close_block() {
  // A block mostly of gaps says little; it is left out rather than given a noisy mean. Past the
  // reserved capacity (a learning period longer than announced) nothing more is kept.
  if (2 * count_ >= hops_in_block_ && blocks_.size() < blocks_.capacity()) {
    blocks_.push_back({first_t_, last_t_, sum_ / static_cast<double>(count_)});
  }
  sum_ = 0.0;
  count_ = hops_in_block_ = 0;
}

std::optional<LearnedChange> IndexStepProbe::judge() const {
  if (blocks_.size() < 2) return std::nullopt;
  const double start = blocks_.front().t_first;
  const double split = start + kReferenceShare * (blocks_.back().t - start);
  std::size_t reference = 0;
  while (reference < blocks_.size() && blocks_[reference].t <= split) ++reference;
  if (reference < 3 || blocks_.size() < reference + options_.min_blocks_after) return std::nullopt;

  // Median, robust spread and lowest block of the reference.
  std::vector<double>& means = scratch_;
  means.clear();
  for (std::size_t i = 0; i < reference; ++i) means.push_back(blocks_[i].mean);
  const double lowest = *std::min_element(means.begin(), means.end());
  auto median_of = [](std::vector<double>& values) {
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
  };
  const double median = median_of(means);
  for (double& value : means) value = std::abs(value - median);
  // A floor on the spread: a reference of a few very steady blocks must not make any wobble a
  // step.
  const double spread = std::max(1.4826 * median_of(means), 0.02 * median);
  if (!(spread > 0.0)) return std::nullopt;

  // The change time that explains the drop best: the largest sum of shortfalls from k on, in
  // standard errors (scanned backwards, one step per candidate).
  std::optional<LearnedChange> best;
  double shortfall = 0.0;
  std::size_t below = 0;
  for (std::size_t k = blocks_.size(); k-- > reference;) {
    shortfall += median - blocks_[k].mean;
    if (blocks_[k].mean < lowest) ++below;
    const std::size_t after = blocks_.size() - k;
    if (after < options_.min_blocks_after) continue;
    const double drop = shortfall / static_cast<double>(after);
    const double z = drop * std::sqrt(static_cast<double>(after)) / spread;
    const bool alarm_worthy =
        drop >= options_.min_spreads * spread && median - drop < lowest &&
        drop >= options_.min_relative_drop * median &&
        static_cast<double>(below) >= options_.min_share_below * static_cast<double>(after);
    if (!alarm_worthy || (best && z <= best->z)) continue;
    best = LearnedChange{blocks_[k].t_first, "index", channel_, drop, median, z};
  }
  return best;
}

}  // namespace leakmon::detect
