#include "detect/index_cusum_detector.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

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
// A hop whose load moved less than this (of supply) is at rest for the supply estimate: there
// p1 + p2 = ps + pt (MODEL.md).
constexpr double kRestActivity = 2e-3;
// A supply reading this far (share of the configured supply) from the estimate for
// kSupplyStepHops consecutive rest hops (at once with a `ps` observation) is a step; the
// chambers follow it within about a second, so hops in the kSupplyTransientSeconds after it are
// not used at all.
constexpr double kSupplyStep = 0.02;
constexpr std::size_t kSupplyStepHops = 10;
constexpr double kSupplyTransientSeconds = 3.0;
constexpr double kSupplyMemorySeconds = 2.0;
// The drift trend needs this many blocks in its reference window to fit a slope; with fewer
// (but at least kTrendLevelBlocks) it uses their level.
constexpr std::size_t kTrendSlopeBlocks = 20;
constexpr std::size_t kTrendLevelBlocks = 3;
// Judged blocks whose CUSUM increments can be taken back after a supply step seen through one
// chamber: the step shows at the end of the first hold that fits neither cluster (holds last up
// to 4 s, a ramp up to 5 s, and a few holds after the step may fit by chance), so within about
// 20 s; the ring covers 48 s.
constexpr std::size_t kCusumHistoryBlocks = 60;

}  // namespace

IndexCusumDetector::IndexCusumDetector(const IndexCusumOptions& options, double hop_seconds)
    : options_(options),
      settle_hops_(options.learning.settle_hops(hop_seconds)),
      learn_hops_(std::max<std::size_t>(options.learning.learn_hops(hop_seconds), 1)),
      block_hops_(std::max<std::size_t>(
          static_cast<std::size_t>(std::lround(options.block_seconds / hop_seconds)), 1)),
      one_chamber_(options.use_p1 != options.use_p2),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds)) {
  learned_.reserve(learn_hops_ / block_hops_ + 1);
  cusum_history_.resize(kCusumHistoryBlocks);
  const double trend_seconds = options.drift_guard_seconds + options.drift_window_seconds +
                               options.supply_settle_seconds + options.block_seconds;
  trend_.resize(static_cast<std::size_t>(std::ceil(trend_seconds / options.block_seconds)) + 2);
  coefficients_[4] = options.temperature_prior;
}

void IndexCusumDetector::reset() {
  hops_seen_ = 0;
  learned_.clear();
  learned_model_ = false;
  std::fill(std::begin(coefficients_), std::end(coefficients_), 0.0);
  coefficients_[4] = options_.temperature_prior;
  block_sigma_ = kMissing;
  block_hop_ = block_valid_ = block_temps_ = 0;
  sum_log_index_ = sum_load_ = sum_load_squared_ = sum_activity_ = 0.0;
  sum_log_ratio_ = sum_log_supply_ = 0.0;
  previous_load_ = previous_rough_load_ = last_expected_ = kMissing;
  temperature_seen_ = false;
  supply_estimate_ = supply_anchor_ = supply_step_since_ = kMissing;
  supply_off_hops_ = 0;
  chamber_supply_.reset();
  learned_supply_ = kMissing;
  cusum_next_ = cusum_count_ = 0;
  cusum_.reset();
  trend_next_ = trend_count_ = 0;
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
double IndexCusumDetector::load_of(const Observation& o, double ps) const {
  const double pt = options_.rig.pt;
  if (options_.use_p1 && options_.use_p2 && !std::isnan(o.p1) && !std::isnan(o.p2)) {
    return (o.p1 - o.p2) / ps;
  }
  if (options_.use_p1 && !std::isnan(o.p1)) return (2.0 * o.p1 - ps - pt) / ps;
  if (options_.use_p2 && !std::isnan(o.p2)) return (ps + pt - 2.0 * o.p2) / ps;
  return kMissing;
}

// The supply from a `ps` observation, or from both chambers at rest; the configured value until
// either exists. A step restarts the settling clock and the drift reference (the index level
// before it belongs to another supply).
double IndexCusumDetector::supply_for(const Observation& o, double load) {
  const double configured = options_.rig.ps;
  if (one_chamber_ && std::isnan(o.ps)) return supply_from_chamber(o, load);
  double reading = kMissing;
  bool direct = false;
  if (!std::isnan(o.ps)) {
    reading = o.ps;
    direct = true;
  } else if (options_.use_p1 && options_.use_p2 && !std::isnan(o.p1) && !std::isnan(o.p2) &&
             std::abs(load - previous_rough_load_) < kRestActivity) {
    reading = o.p1 + o.p2 - options_.rig.pt;
  }
  previous_rough_load_ = load;
  if (std::isnan(reading)) return std::isnan(supply_estimate_) ? configured : supply_estimate_;
  if (std::isnan(supply_estimate_)) {
    supply_estimate_ = supply_anchor_ = reading;
  } else if (!direct && std::abs(reading - supply_estimate_) > kSupplyStep * configured) {
    // A rest reading far from the estimate: a step if it persists (not one odd hop).
    if (++supply_off_hops_ >= kSupplyStepHops) {
      supply_estimate_ = reading;
      supply_off_hops_ = 0;
    }
  } else {
    supply_off_hops_ = 0;
    const double memory = direct
                              ? 0.0
                              : std::exp(-options_.block_seconds /
                                         static_cast<double>(block_hops_) / kSupplyMemorySeconds);
    supply_estimate_ = memory * supply_estimate_ + (1.0 - memory) * reading;
  }
  // Judged against the supply the reference was anchored at, so that a ramp is a step too.
  if (std::abs(supply_estimate_ - supply_anchor_) > kSupplyStep * configured) {
    supply_anchor_ = supply_estimate_;
    supply_step_since_ = o.t;
    trend_count_ = trend_next_ = 0;
  }
  return supply_estimate_;
}

// One chamber's hold levels (ChamberSupplyTracker). The blocks judged after a step began were
// judged against the old supply: their CUSUM increments are taken back.
double IndexCusumDetector::supply_from_chamber(const Observation& o, double load) {
  const double configured = options_.rig.ps;
  const bool still = std::abs(load - previous_rough_load_) < kRestActivity;  // false with a NaN
  previous_rough_load_ = load;
  switch (chamber_supply_.add(o.t, options_.use_p1 ? o.p1 : o.p2, still)) {
    case ChamberSupplyTracker::Event::step:
      take_back_cusum_after(chamber_supply_.step_time());
      trend_count_ = trend_next_ = 0;
      break;
    case ChamberSupplyTracker::Event::estimated: {
      // Nothing was judged while waiting; the step may have begun earlier than first thought.
      take_back_cusum_after(chamber_supply_.step_time());
      // ps + pt = 2 mid: the supply moved by twice mid-supply's shift since learning.
      const double learned = std::isnan(learned_supply_) ? configured : learned_supply_;
      supply_estimate_ = supply_anchor_ =
          std::max(learned + 2.0 * chamber_supply_.mid_shift(), 0.1 * configured);
      supply_step_since_ = o.t;
      trend_count_ = trend_next_ = 0;
      break;
    }
    case ChamberSupplyTracker::Event::none:
      break;
  }
  return std::isnan(supply_estimate_) ? configured : supply_estimate_;
}

void IndexCusumDetector::take_back_cusum_after(double t) {
  // The oldest remembered block after t (the ring's oldest if all are): the CUSUM before it.
  const CusumEntry* first = nullptr;
  for (std::size_t i = 0; i < cusum_count_; ++i) {
    const CusumEntry& e = cusum_history_[i];
    if (e.t > t && (first == nullptr || e.t < first->t)) first = &e;
  }
  if (first != nullptr) cusum_.restore(first->before);
}

double IndexCusumDetector::expected_log_index(const Block& b) const {
  return coefficients_[0] + coefficients_[1] * b.load + coefficients_[2] * b.load_squared +
         coefficients_[3] * b.log_activity + coefficients_[4] * b.log_friction +
         options_.supply_exponent * b.log_supply;
}

// Adds one hop; true when a block completed with enough valid hops (then `completed` holds it).
bool IndexCusumDetector::add_to_block(const Observation& o, double log_index, double load,
                                      double supply, Block& completed) {
  const double activity = std::abs(load - previous_load_);
  previous_load_ = load;
  const bool settled =
      (std::isnan(supply_step_since_) || o.t - supply_step_since_ >= kSupplyTransientSeconds) &&
      !chamber_supply_.awaiting();
  const bool temperature_ok = !temperature_seen_ || !std::isnan(o.temp);
  if (!std::isnan(log_index) && !std::isnan(activity) && settled && temperature_ok) {
    sum_log_index_ += log_index;
    sum_load_ += load;
    sum_load_squared_ += load * load;
    sum_activity_ += activity;
    sum_log_supply_ += std::log(supply);
    // The viscous friction's share of the damping, b(T) = b (0.5 + 0.5 / r) (MODEL.md).
    if (temperature_seen_)
      sum_log_ratio_ -= std::log(sim::friction_factor(options_.oil.ratio(o.temp)));
    ++block_valid_;
  }
  if (++block_hop_ < block_hops_) return false;
  const bool enough = 2 * block_valid_ >= block_hops_;
  if (enough) {
    const double n = static_cast<double>(block_valid_);
    completed = {o.t,
                 sum_log_index_ / n,
                 sum_load_ / n,
                 sum_load_squared_ / n,
                 std::log(sum_activity_ / n + kActivityFloor),
                 sum_log_ratio_ / n,
                 sum_log_supply_ / n};
  }
  block_hop_ = block_valid_ = 0;
  sum_log_index_ = sum_load_ = sum_load_squared_ = sum_activity_ = 0.0;
  sum_log_ratio_ = sum_log_supply_ = 0.0;
  return enough;
}

void IndexCusumDetector::finish_learning() {
  learned_model_ = true;
  learned_supply_ = std::isnan(supply_estimate_) ? options_.rig.ps : supply_estimate_;
  if (one_chamber_) chamber_supply_.learn();
  if (learned_.size() < 2 * kRegressors) return;  // too little data: never judges
  // The supply's share is physical (supply_exponent), not learned: the learning period rarely
  // sees more than one supply.
  const double exponent = options_.supply_exponent;
  auto response = [exponent](const Block& b) { return b.log_index - exponent * b.log_supply; };
  // First without the temperature: the spread that weighs the prior.
  LeastSquares<4> plain;
  for (const auto& b : learned_) {
    plain.add(Eigen::Vector4d(1.0, b.load, b.load_squared, b.log_activity), response(b));
  }
  const Eigen::Vector4d beta4 = plain.solve();
  for (int i = 0; i < 4; ++i) coefficients_[i] = beta4[i];
  coefficients_[4] = options_.temperature_prior;
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
    const double rho = sum_sq > 0.0 ? std::clamp(sum_lag / sum_sq, 0.0, 0.8) : 0.0;
    const double weight = std::sqrt(plain.residual_variance(beta4) * (1.0 + rho) / (1.0 - rho)) /
                          std::max(options_.temperature_prior_sigma, 1e-9);
    Vector5 prior = Vector5::Zero();
    prior[4] = weight;
    fit.add(prior, weight * options_.temperature_prior);
    const Vector5 beta = fit.solve();
    for (int i = 0; i < kRegressors; ++i) coefficients_[i] = beta[i];
  }
  double sum_sq = 0.0, sum_lag = 0.0, previous = kMissing;
  for (const auto& b : learned_) {
    const double r = b.log_index - expected_log_index(b);
    remember_block(b.t, r);
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

void IndexCusumDetector::remember_block(double t, double residual) {
  trend_[trend_next_] = {t, residual};
  trend_next_ = (trend_next_ + 1) % trend_.size();
  trend_count_ = std::min(trend_count_ + 1, trend_.size());
}

// Least squares of residual = a + b (t_k - t) over the reference window: a is the healthy level
// now. The window ends drift_guard_seconds ago, or where the re-anchoring after the last supply
// step ended if that is later (its blocks are all the reference there is). The extrapolation is
// bounded by the designed drop, so a trend fitted to a few noisy blocks can never carry the
// reference further than a leak.
double IndexCusumDetector::drift_reference(double t) const {
  if (!(options_.drift_window_seconds > 0.0) && std::isnan(supply_step_since_)) return 0.0;
  double newest = t - options_.drift_guard_seconds;
  if (!std::isnan(supply_step_since_)) {
    newest = std::max(newest, supply_step_since_ + options_.supply_settle_seconds);
  }
  const double oldest = t - options_.drift_guard_seconds - options_.drift_window_seconds;
  double s = 0.0, st = 0.0, stt = 0.0, r = 0.0, rt = 0.0, earliest = t;
  std::size_t n = 0;
  for (std::size_t i = 0; i < trend_count_; ++i) {
    const TrendBlock& b = trend_[i];
    if (b.t > newest || (b.t < oldest && options_.drift_window_seconds > 0.0)) continue;
    const double tau = b.t - t;
    s += 1.0;
    st += tau;
    stt += tau * tau;
    r += b.residual;
    rt += b.residual * tau;
    earliest = std::min(earliest, b.t);
    ++n;
  }
  if (n < kTrendLevelBlocks) return 0.0;
  const double level = r / s;  // at the window's centre
  // With a temperature the model follows the oil itself and only a slow remainder is left: the
  // level suffices, and a slope extrapolated over the guard would only add its noise.
  // A slope also needs the window's full length (after a supply step it refills): over a
  // shorter span its noise, extrapolated over the guard, would exceed the drift it follows.
  if (n < kTrendSlopeBlocks || !(options_.drift_window_seconds > 0.0) || temperature_seen_ ||
      newest - earliest < 0.9 * options_.drift_window_seconds) {
    return level;
  }
  const double det = s * stt - st * st;
  if (!(det > 0.0)) return level;
  // Slope of the trend and its variance (blocks with the learned long-run spread). A slope that
  // the window barely identifies would carry its noise over the guard (with the default window
  // about as much as the designed drop), so it is shrunk by b^2 / (b^2 + var b): a clear trend
  // is followed, noise is not.
  const double slope = (s * rt - st * r) / det;
  const double slope_variance = block_sigma_ * block_sigma_ * s / det;
  const double shrink = slope * slope / (slope * slope + slope_variance);
  const double extrapolated = level - shrink * slope * (st / s);
  const double bound = -std::log1p(-options_.design_drop);
  return level + std::clamp(extrapolated - level, -bound, bound);
}

Decision IndexCusumDetector::update(const Observation& observation) {
  Decision decision;
  const double log_index = log_index_of(observation);
  decision.index = std::isnan(log_index) ? kMissing : std::exp(log_index);
  ++hops_seen_;
  if (!learned_model_) {
    const std::size_t total = settle_hops_ + learn_hops_;
    decision.learning_hops_left = static_cast<double>(hops_seen_ >= total ? 0 : total - hops_seen_);
  }
  if (hops_seen_ <= settle_hops_) return decision;
  if (!std::isnan(observation.temp)) temperature_seen_ = true;

  const double rough_load = load_of(observation, options_.rig.ps);
  const double supply = supply_for(observation, rough_load);
  Block block{};
  const bool completed =
      add_to_block(observation, log_index, load_of(observation, supply), supply, block);
  if (!learned_model_) {
    if (completed) learned_.push_back(block);  // capacity reserved: never reallocates
    if (hops_seen_ - settle_hops_ >= learn_hops_) finish_learning();
    return decision;
  }
  decision.learning = false;
  if (std::isnan(block_sigma_) || !(block_sigma_ > 0.0)) return decision;
  if (completed && !chamber_supply_.awaiting()) {
    const double residual = block.log_index - expected_log_index(block);
    const double reference = drift_reference(block.t);
    last_expected_ = expected_log_index(block) + reference;
    const bool anchoring = !std::isnan(supply_step_since_) &&
                           block.t - supply_step_since_ < options_.supply_settle_seconds;
    if (anchoring) {
      remember_block(block.t, residual);
    } else {
      // Log-likelihood ratio of "mean residual is log(1 - design_drop)" against
      // "log(1 - min_drop)", per block.
      const double null_shift = std::log1p(-options_.min_drop) / block_sigma_;
      const double shift = std::log1p(-options_.design_drop) / block_sigma_;  // more negative
      const double z = (residual - reference) / block_sigma_;
      cusum_history_[cusum_next_] = {block.t, cusum_.value()};
      cusum_next_ = (cusum_next_ + 1) % cusum_history_.size();
      cusum_count_ = std::min(cusum_count_ + 1, cusum_history_.size());
      cusum_.add((shift - null_shift) * (z - (shift + null_shift) / 2.0));
      // Blocks under suspicion stay out of the reference: a leak is never learned as drift.
      if (cusum_.normalised() < 0.5) remember_block(block.t, residual);
    }
  }
  decision.baseline = std::isnan(last_expected_) ? kMissing : std::exp(last_expected_);
  decision.score = cusum_.normalised();
  return decision;
}

}  // namespace leakmon::detect

namespace leakmon::detect {

namespace {
constexpr int kIndexStateVersion =
    3;  // 2: drift reference, temperature, supply; 3: one chamber's supply
constexpr std::size_t kBlockValues = 7;
}  // namespace

DetectorState IndexCusumDetector::export_state() const {
  DetectorState state(std::string(name()), kIndexStateVersion);
  state.put_count("hops_seen", hops_seen_);
  std::vector<double> learned;
  learned.reserve(learned_.size() * kBlockValues);
  for (const auto& b : learned_) {
    learned.insert(learned.end(), {b.t, b.log_index, b.load, b.load_squared, b.log_activity,
                                   b.log_friction, b.log_supply});
  }
  state.put("learned_blocks", learned);
  state.put("learned_model", learned_model_ ? 1.0 : 0.0);
  state.put("coefficients", coefficients_);
  state.put("learned_log_supply", learned_log_supply_);
  state.put("block_sigma", block_sigma_);
  state.put_count("block_hop", block_hop_);
  state.put_count("block_valid", block_valid_);
  state.put_count("block_temps", block_temps_);
  state.put("block_sums", std::vector<double>{sum_log_index_, sum_load_, sum_load_squared_,
                                              sum_activity_, sum_log_ratio_, sum_log_supply_});
  state.put("previous_load", previous_load_);
  state.put("previous_rough_load", previous_rough_load_);
  state.put("last_expected", last_expected_);
  state.put("temperature_seen", temperature_seen_ ? 1.0 : 0.0);
  state.put("supply", std::vector<double>{supply_estimate_, supply_anchor_, supply_step_since_});
  state.put_count("supply_off_hops", supply_off_hops_);
  state.put("cusum", cusum_.value());
  std::vector<double> trend;
  trend.reserve(trend_.size() * 2);
  for (const auto& b : trend_) trend.insert(trend.end(), {b.t, b.residual});
  state.put("trend", trend);
  state.put_count("trend_next", trend_next_);
  state.put_count("trend_count", trend_count_);
  state.put("chamber_supply", chamber_supply_.export_values());
  state.put("learned_supply", learned_supply_);
  std::vector<double> history;
  history.reserve(cusum_history_.size() * 2);
  for (const auto& e : cusum_history_) history.insert(history.end(), {e.t, e.before});
  state.put("cusum_history", history);
  state.put_count("cusum_next", cusum_next_);
  state.put_count("cusum_count", cusum_count_);
  return state;
}

void IndexCusumDetector::import_state(const DetectorState& state) {
  reset();
  try {
    state.expect(name(), kIndexStateVersion);
    auto list = [&](const char* key, std::size_t size) -> const std::vector<double>& {
      const auto& values = state.get_list(key);
      if (values.size() != size) {
        throw StateError(std::string("index_cusum: '") + key + "' has the wrong length");
      }
      return values;
    };
    const auto& learned = state.get_list("learned_blocks");
    if (learned.size() % kBlockValues != 0 || learned.size() / kBlockValues > learned_.capacity()) {
      throw StateError("index_cusum: learned blocks do not fit this configuration");
    }
    const auto& coefficients = list("coefficients", kRegressors);
    const auto& sums = list("block_sums", 6);
    const auto& supply = list("supply", 3);
    const auto& trend = list("trend", trend_.size() * 2);
    const double cusum = state.get("cusum");
    if (!std::isfinite(cusum)) throw StateError("index_cusum: CUSUM not finite");
    hops_seen_ = state.get_count("hops_seen");
    for (std::size_t i = 0; i < learned.size(); i += kBlockValues) {
      learned_.push_back({learned[i], learned[i + 1], learned[i + 2], learned[i + 3],
                          learned[i + 4], learned[i + 5], learned[i + 6]});
    }
    learned_model_ = state.get("learned_model") != 0.0;
    std::copy(coefficients.begin(), coefficients.end(), coefficients_);
    learned_log_supply_ = state.get("learned_log_supply");
    block_sigma_ = state.get("block_sigma");
    block_hop_ = state.get_count("block_hop");
    block_valid_ = state.get_count("block_valid");
    block_temps_ = state.get_count("block_temps");
    if (block_hop_ >= block_hops_ || block_valid_ > block_hop_ || block_temps_ > block_hop_) {
      throw StateError("index_cusum: block position out of range");
    }
    sum_log_index_ = sums[0];
    sum_load_ = sums[1];
    sum_load_squared_ = sums[2];
    sum_activity_ = sums[3];
    sum_log_ratio_ = sums[4];
    sum_log_supply_ = sums[5];
    previous_load_ = state.get("previous_load");
    previous_rough_load_ = state.get("previous_rough_load");
    last_expected_ = state.get("last_expected");
    temperature_seen_ = state.get("temperature_seen") != 0.0;
    supply_estimate_ = supply[0];
    supply_anchor_ = supply[1];
    supply_step_since_ = supply[2];
    supply_off_hops_ = state.get_count("supply_off_hops");
    cusum_.restore(cusum);
    const std::size_t trend_next = state.get_count("trend_next");
    const std::size_t trend_count = state.get_count("trend_count");
    if (trend_next >= trend_.size() || trend_count > trend_.size()) {
      throw StateError("index_cusum: trend position out of range");
    }
    for (std::size_t i = 0; i < trend_.size(); ++i) trend_[i] = {trend[2 * i], trend[2 * i + 1]};
    trend_next_ = trend_next;
    trend_count_ = trend_count;
    chamber_supply_.import_values(state.get_list("chamber_supply"));
    learned_supply_ = state.get("learned_supply");
    const auto& history = list("cusum_history", cusum_history_.size() * 2);
    const std::size_t cusum_next = state.get_count("cusum_next");
    const std::size_t cusum_count = state.get_count("cusum_count");
    if (cusum_next >= cusum_history_.size() || cusum_count > cusum_history_.size()) {
      throw StateError("index_cusum: CUSUM history position out of range");
    }
    for (std::size_t i = 0; i < cusum_history_.size(); ++i) {
      cusum_history_[i] = {history[2 * i], history[2 * i + 1]};
    }
    cusum_next_ = cusum_next;
    cusum_count_ = cusum_count;
  } catch (...) {
    reset();
    throw;
  }
}

// The drift reference and the supply transient are on the old source clock; the hop before the
// gap is not a neighbour of the next one.
void IndexCusumDetector::resume_after_gap() {
  trend_next_ = trend_count_ = 0;
  supply_step_since_ = kMissing;
  supply_off_hops_ = 0;
  previous_load_ = previous_rough_load_ = kMissing;
  chamber_supply_.resume_after_gap();
  cusum_next_ = cusum_count_ = 0;
}

}  // namespace leakmon::detect
