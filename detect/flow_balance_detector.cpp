#include "detect/flow_balance_detector.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "detect/least_squares.hpp"

namespace leakmon::detect {

namespace {

double sign_of(double value) { return value > 0.0 ? 1.0 : (value < 0.0 ? -1.0 : 0.0); }

// A change of the supply (or of its rest-sum estimate) by more than this share of the
// configured supply is a transient: blocks are not judged until it has settled for
// kSupplySettleSeconds (the chambers follow the supply at rest within about a second).
constexpr double kSupplyStep = 0.02;
constexpr double kSupplySettleSeconds = 3.0;
// Memory of the rest-sum supply estimate between steps.
constexpr double kSupplySeconds = 2.0;
// The drift trend needs this many blocks in its reference window to fit a slope; with fewer
// (but at least kTrendLevelBlocks) it uses their level.
constexpr std::size_t kTrendSlopeBlocks = 20;
constexpr std::size_t kTrendLevelBlocks = 3;

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
      floor_slope_(options.min_leak * std::sqrt(options.rig.ps) / options.rig.Kv),
      sizing_decay_(std::exp(-options.block_seconds / options.sizing_seconds)),
      cusum_(cusum_threshold_for(options.false_alarms_per_hour, options.block_seconds)) {
  learned_.reserve(learn_hops_);
  scratch_.reserve(learn_hops_);
  const double trend_seconds =
      options.drift_guard_seconds + options.drift_window_seconds + options.block_seconds;
  trend_.resize(static_cast<std::size_t>(std::ceil(trend_seconds / options.block_seconds)) + 2);
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
  supply_estimate_ = supply_settled_since_ = kMissing;
  temperature_seen_ = false;
  trend_next_ = trend_count_ = 0;
}

void FlowBalanceDetector::remember_block(double t, double residual, double leak_term) {
  trend_[trend_next_] = {t, residual, leak_term};
  trend_next_ = (trend_next_ + 1) % trend_.size();
  trend_count_ = std::min(trend_count_ + 1, trend_.size());
}

// Weighted least squares of residual = leak_term (a + b (t_k - t)) over the reference window:
// a is the healthy slope now. The extrapolation is bounded by the leak floor, so a trend fitted
// to a few noisy blocks can never carry the reference further than a leak of interest.
double FlowBalanceDetector::drift_slope(double t) const {
  const double newest = t - options_.drift_guard_seconds;
  const double oldest = newest - options_.drift_window_seconds;
  double ll = 0.0, llt = 0.0, lltt = 0.0, rl = 0.0, rlt = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < trend_count_; ++i) {
    const TrendBlock& b = trend_[i];
    if (b.t < oldest || b.t > newest) continue;
    const double tau = b.t - t, l2 = b.leak_term * b.leak_term;
    ll += l2;
    llt += l2 * tau;
    lltt += l2 * tau * tau;
    rl += b.residual * b.leak_term;
    rlt += b.residual * b.leak_term * tau;
    ++n;
  }
  if (n < kTrendLevelBlocks || !(ll > 0.0)) return 0.0;
  const double level_now = rl / ll;  // the window's level, if no slope can be fitted
  if (n < kTrendSlopeBlocks) return level_now;
  const double det = ll * lltt - llt * llt;
  if (!(det > 0.0)) return level_now;
  const double extrapolated = (rl * lltt - rlt * llt) / det;
  const double level = rl / ll;  // at the window's weighted centre
  return level + std::clamp(extrapolated - level, -floor_slope_, floor_slope_);
}

double FlowBalanceDetector::supply_for(const Observation& o, double speed) {
  const double configured = options_.rig.ps;
  double reading = kMissing;
  if (!std::isnan(o.ps)) {
    reading = o.ps;
  } else if (options_.estimate_supply && !std::isnan(o.p1) && !std::isnan(o.p2) &&
             std::abs(speed) < options_.rest_speed &&
             std::abs(pending_.speed) < options_.rest_speed) {
    // At rest the valve's lands balance: p1 + p2 = ps + pt (MODEL.md).
    reading = o.p1 + o.p2 - options_.rig.pt;
  }
  if (!std::isnan(reading)) {
    if (std::isnan(supply_estimate_) ||
        std::abs(reading - supply_estimate_) > kSupplyStep * configured) {
      if (!std::isnan(supply_estimate_)) supply_settled_since_ = o.t;
      supply_estimate_ = reading;
    } else {
      const double memory = std::isnan(o.ps) ? std::exp(-hop_seconds_ / kSupplySeconds) : 0.0;
      supply_estimate_ = memory * supply_estimate_ + (1.0 - memory) * reading;
    }
  }
  return std::isnan(supply_estimate_) ? configured : supply_estimate_;
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
    double residual_sum = 0.0, leak_term_sum = 0.0;
    for (; j < learned_.size() && learned_[j].block == learned_[i].block; ++j) {
      if (!on_flow_branch(learned_[j].hop)) continue;
      residual_sum += learned_[j].hop.opening - expected_opening(learned_[j].hop);
      leak_term_sum += learned_[j].hop.leak_term;
      ++kept;
    }
    if (kept >= min_rest_hops_) {
      const double mean = residual_sum / static_cast<double>(kept);
      remember_block(learned_[j - 1].hop.t, mean, leak_term_sum / static_cast<double>(kept));
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

void FlowBalanceDetector::judge_block(double t, double mean_residual, double mean_leak_term) {
  // Log-likelihood ratio of "residual = design_slope * leak term" against "residual = 0", in units
  // of the block spread. The designed shift is capped at kMaxShift spreads and the residual
  // winsorised at kMaxZ: one odd block (a disturbance the balance does not model) can then
  // add at most kMaxShift * (kMaxZ - kMaxShift / 2), well below the threshold.
  // The null hypothesis is a leak of min_leak (the floor), so the statistic drifts down below
  // it: z is the block's residual beyond the floor's.
  constexpr double kMaxShift = 3.0, kMaxZ = 4.0;
  const double reference = follows_drift() ? drift_slope(t) : 0.0;
  const double excess = mean_residual - reference * mean_leak_term;
  const double shift =
      std::clamp(design_slope_ * mean_leak_term / block_sigma_, -kMaxShift, kMaxShift);
  const double floor = floor_slope_ * mean_leak_term / block_sigma_;
  const double z = std::clamp(excess / block_sigma_ - floor, -kMaxZ, kMaxZ);
  const bool was_quiet = cusum_.value() <= 0.0;
  cusum_.add(shift * (z - shift / 2.0));
  // Blocks under suspicion stay out of the drift reference, so a leak is never learned as drift.
  if (cusum_.normalised() < 0.5) remember_block(t, mean_residual, mean_leak_term);

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
  const bool supply_settled =
      std::isnan(supply_settled_since_) || o.t - supply_settled_since_ >= kSupplySettleSeconds;
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
  ++hops_seen_;
  if (!learned_model_) {
    const std::size_t total = settle_hops_ + learn_hops_;
    decision.learning_hops_left = static_cast<double>(hops_seen_ >= total ? 0 : total - hops_seen_);
  }
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
      judge_block(hop.t, block_residual_sum_ / n, block_leak_term_sum_ / n);
    }
    block_hop_ = block_rest_hops_ = 0;
    block_residual_sum_ = block_leak_term_sum_ = 0.0;
  }
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

constexpr int kFlowStateVersion = 2;
constexpr std::size_t kHopValues = 9;

}  // namespace

DetectorState FlowBalanceDetector::export_state() const {
  DetectorState state(std::string(name()), kFlowStateVersion);
  auto put_hop = [](std::vector<double>& out, const Hop& h) {
    out.insert(out.end(), {h.t, h.opening, h.load, h.root, h.leak_term, h.speed, h.supply,
                           h.viscosity_ratio, h.usable ? 1.0 : 0.0});
  };
  auto hop_values = [&](const Hop& h) {
    std::vector<double> v;
    put_hop(v, h);
    return v;
  };
  state.put_count("observations", observations_);
  state.put_count("hops_seen", hops_seen_);
  state.put("previous_x", previous_x_);
  state.put("before", hop_values(before_));
  state.put("pending", hop_values(pending_));
  std::vector<double> learned;
  learned.reserve(learned_.size() * (kHopValues + 1));
  for (const auto& rest : learned_) {
    put_hop(learned, rest.hop);
    learned.push_back(static_cast<double>(rest.block));
  }
  state.put("learned_rest_hops", learned);
  state.put("learned_model", learned_model_ ? 1.0 : 0.0);
  state.put("positive_loads",
            std::vector<double>{positive_loads_.low, positive_loads_.high, positive_loads_.middle});
  state.put("negative_loads",
            std::vector<double>{negative_loads_.low, negative_loads_.high, negative_loads_.middle});
  state.put("coefficients",
            std::vector<double>(coefficients_.data(), coefficients_.data() + coefficients_.size()));
  state.put("hop_sigma", hop_sigma_);
  state.put("block_sigma", block_sigma_);
  state.put_count("block_hop", block_hop_);
  state.put_count("block_rest_hops", block_rest_hops_);
  state.put("block_sums", std::vector<double>{block_residual_sum_, block_leak_term_sum_});
  for (const auto& [key, sums] :
       {std::pair{"weighted", &weighted_}, std::pair{"since_change", &since_change_},
        std::pair{"change_block", &change_block_}}) {
    state.put(key, std::vector<double>{sums->rl, sums->ll, sums->ll_sq});
  }
  state.put("cusum", cusum_.value());
  state.put("last_decision",
            std::vector<double>{last_.score, last_.learning ? 1.0 : 0.0, last_.baseline,
                                last_.index, last_.leak_coefficient, last_.leak_coefficient_ci,
                                last_.viscosity_ratio});
  state.put("supply", std::vector<double>{supply_estimate_, supply_settled_since_});
  state.put("temperature_seen", temperature_seen_ ? 1.0 : 0.0);
  std::vector<double> trend;
  trend.reserve(trend_.size() * 3);
  for (const auto& b : trend_) trend.insert(trend.end(), {b.t, b.residual, b.leak_term});
  state.put("trend", trend);
  state.put_count("trend_next", trend_next_);
  state.put_count("trend_count", trend_count_);
  return state;
}

void FlowBalanceDetector::import_state(const DetectorState& state) {
  reset();
  try {
    state.expect(name(), kFlowStateVersion);
    auto list = [&](const char* key, std::size_t size) -> const std::vector<double>& {
      const auto& values = state.get_list(key);
      if (values.size() != size) {
        throw StateError(std::string("flow_balance: '") + key + "' has the wrong length");
      }
      return values;
    };
    auto hop_at = [](const double* v) {
      Hop h;
      h.t = v[0];
      h.opening = v[1];
      h.load = v[2];
      h.root = v[3];
      h.leak_term = v[4];
      h.speed = v[5];
      h.supply = v[6];
      h.viscosity_ratio = v[7];
      h.usable = v[8] != 0.0;
      return h;
    };
    const auto& learned = state.get_list("learned_rest_hops");
    if (learned.size() % (kHopValues + 1) != 0 ||
        learned.size() / (kHopValues + 1) > learned_.capacity()) {
      throw StateError("flow_balance: learned hops do not fit this configuration");
    }
    const double cusum = state.get("cusum");
    if (!std::isfinite(cusum)) throw StateError("flow_balance: CUSUM not finite");
    observations_ = state.get_count("observations");
    hops_seen_ = state.get_count("hops_seen");
    previous_x_ = state.get("previous_x");
    before_ = hop_at(list("before", kHopValues).data());
    pending_ = hop_at(list("pending", kHopValues).data());
    for (std::size_t i = 0; i < learned.size(); i += kHopValues + 1) {
      const double block = learned[i + kHopValues];
      if (!(block >= 0.0) || std::floor(block) != block) {
        throw StateError("flow_balance: block number is not a count");
      }
      learned_.push_back({hop_at(&learned[i]), static_cast<std::size_t>(block)});
    }
    learned_model_ = state.get("learned_model") != 0.0;
    const auto& positive = list("positive_loads", 3);
    const auto& negative = list("negative_loads", 3);
    positive_loads_ = {positive[0], positive[1], positive[2]};
    negative_loads_ = {negative[0], negative[1], negative[2]};
    const auto& coefficients = list("coefficients", kTerms);
    for (int i = 0; i < kTerms; ++i) coefficients_[i] = coefficients[static_cast<std::size_t>(i)];
    hop_sigma_ = state.get("hop_sigma");
    block_sigma_ = state.get("block_sigma");
    block_hop_ = state.get_count("block_hop");
    block_rest_hops_ = state.get_count("block_rest_hops");
    if (block_hop_ >= block_hops_ || block_rest_hops_ > block_hop_) {
      throw StateError("flow_balance: block position out of range");
    }
    const auto& block_sums = list("block_sums", 2);
    block_residual_sum_ = block_sums[0];
    block_leak_term_sum_ = block_sums[1];
    for (const auto& [key, sums] :
         {std::pair{"weighted", &weighted_}, std::pair{"since_change", &since_change_},
          std::pair{"change_block", &change_block_}}) {
      const auto& v = list(key, 3);
      *sums = SlopeSums{v[0], v[1], v[2]};
    }
    cusum_.restore(cusum);
    const auto& trend = list("trend", trend_.size() * 3);
    const std::size_t trend_next = state.get_count("trend_next");
    const std::size_t trend_count = state.get_count("trend_count");
    if (trend_next >= trend_.size() || trend_count > trend_.size()) {
      throw StateError("flow_balance: trend position out of range");
    }
    for (std::size_t i = 0; i < trend_.size(); ++i) {
      trend_[i] = {trend[3 * i], trend[3 * i + 1], trend[3 * i + 2]};
    }
    trend_next_ = trend_next;
    trend_count_ = trend_count;
    const auto& supply = list("supply", 2);
    supply_estimate_ = supply[0];
    supply_settled_since_ = supply[1];
    temperature_seen_ = state.get("temperature_seen") != 0.0;
    const auto& d = list("last_decision", 7);
    last_.score = d[0];
    last_.learning = d[1] != 0.0;
    last_.baseline = d[2];
    last_.index = d[3];
    last_.leak_coefficient = d[4];
    last_.leak_coefficient_ci = d[5];
    last_.viscosity_ratio = d[6];
  } catch (...) {
    reset();
    throw;
  }
}

// The drift trend and the supply transient are on the old source clock; the hops before the
// gap are not neighbours of the next ones.
void FlowBalanceDetector::resume_after_gap() {
  trend_next_ = trend_count_ = 0;
  supply_settled_since_ = kMissing;
  previous_x_ = kMissing;
  before_ = pending_ = Hop{};
}

}  // namespace leakmon::detect
