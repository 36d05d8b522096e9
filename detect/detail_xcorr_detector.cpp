#include "detect/detail_xcorr_detector.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "detect/legacy_state.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::detect {

namespace {

// Full convolution of a and b into out (out.size() >= a.size() + b.size() - 1); returns its
// length. Construction only.
std::size_t convolve(std::span<const double> a, std::span<const double> b, std::span<double> out) {
  const std::size_t n = a.size() + b.size() - 1;
  std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n), 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
  }
  return n;
}

// The filter with a zero between taps `factor - 1` times (the a trous upsampling).
std::vector<double> upsampled(std::span<const double> f, std::size_t factor) {
  std::vector<double> out((f.size() - 1) * factor + 1, 0.0);
  for (std::size_t i = 0; i < f.size(); ++i) out[i * factor] = f[i];
  return out;
}

// Stores filter f (applied as y[n] = sum f[k] x[n - k]) time-reversed and right-aligned, so that
// its output is the dot product with the newest kTaps samples, oldest first.
template <std::size_t N>
void store_reversed(std::span<const double> f, std::array<double, N>& out) {
  out.fill(0.0);
  for (std::size_t k = 0; k < f.size(); ++k) out[N - 1 - k] = f[k];
}

template <std::size_t N>
double dot(const std::array<double, N>& filter, const double* samples) {
  double sum = 0.0;
  for (std::size_t i = 0; i < N; ++i) sum += filter[i] * samples[i];
  return sum;
}

// The test's physics: shifts in the feature's units (oriented so that a leak lowers it), no
// supply exponent and no temperature (the feature is a ratio: the supply's and the oil's
// effects on the index's size cancel in it; what is left of them the regression and the drift
// reference follow).
//
// The shifts are ln(1 - (1 - e^-shift)), and the test sees ln(e^feature): this detector first
// ran on the index's test with exp(feature) as its "index" and the shift as a relative drop of
// it; the round trips, which move the values by an ulp or so, are kept so that its events stay
// the same to the byte (issue 26). Issue 23 may drop them.
FeaturePhysics xcorr_physics(const DetailXcorrOptions& o, bool correlation) {
  const double design = correlation ? o.design_shift_correlation : o.design_shift_ratio;
  const double floor = correlation ? o.min_shift_correlation : o.min_shift_ratio;
  FeaturePhysics physics;
  physics.threshold_from_spread = true;
  physics.design_shift = std::log1p(std::expm1(-design));
  physics.null_shift = std::log1p(std::expm1(-floor));
  physics.supply_exponent = 0.0;
  physics.uses_temperature = false;
  physics.temperature_prior = 0.0;
  return physics;
}

double as_test_value(double oriented) {
  const double e = std::exp(oriented);
  return e > 0.0 ? std::log(e) : kMissing;
}

std::size_t window_hops_of(const DetailXcorrOptions& o) {
  return std::clamp<std::size_t>(o.window_hops, 1, DetailXcorrDetector::kMaxWindowHops);
}

}  // namespace

DetailXcorrDetector::DetailXcorrDetector(const DetailXcorrOptions& options, double hop_seconds)
    : options_(options),
      hop_seconds_(hop_seconds),
      correlation_(options.use_p1 && options.use_p2),
      use_p2_alone_(!options.use_p1 && options.use_p2),
      hops_(window_hops_of(options)),
      test_(options, xcorr_physics(options, options.use_p1 && options.use_p2), hop_seconds) {
  options_.window_hops = hops_.capacity();
  const auto& db8 = dsp::wavelet("db8");
  const std::span<const double> lo = db8.dec_lo, hi = db8.dec_hi;
  std::array<double, kTaps> two{}, three{}, scratch{};
  // Level 2: h * (g up 2). Level 3: h * (h up 2) * (g up 4).
  const std::size_t n2 = convolve(lo, upsampled(hi, 2), two);
  const std::size_t n_lo2 = convolve(lo, upsampled(lo, 2), scratch);
  const std::size_t n3 =
      convolve(std::span<const double>(scratch.data(), n_lo2), upsampled(hi, 4), three);
  store_reversed(hi, level1_);
  store_reversed(std::span<const double>(two.data(), n2), level2_);
  store_reversed(std::span<const double>(three.data(), n3), level3_);
}

void DetailXcorrDetector::restart_filters() {
  primed_ = 0;
  hops_.clear();
}

void DetailXcorrDetector::reset() {
  restart_filters();
  a_ = History{};
  b_ = History{};
  last_t_ = kMissing;
  test_.reset();
}

void DetailXcorrDetector::resume_after_gap() {
  restart_filters();
  last_t_ = kMissing;
  test_.resume_after_gap();
}

double DetailXcorrDetector::feature() const {
  if (!hops_.full()) return kMissing;
  HopSums total;
  for (std::size_t i = 0; i < hops_.size(); ++i) {
    const HopSums& h = hops_.oldest(i);
    total.aa += h.aa;
    total.bb += h.bb;
    total.ab += h.ab;
    total.e1 += h.e1;
    total.e3 += h.e3;
  }
  if (correlation_) {
    if (!(total.aa > 0.0 && total.bb > 0.0)) return kMissing;
    return total.ab / std::sqrt(total.aa * total.bb);
  }
  if (!(total.aa > 0.0 && total.e1 > 0.0 && total.e3 > 0.0)) return kMissing;
  return std::log(total.aa) - 0.5 * (std::log(total.e1) + std::log(total.e3));
}

Decision DetailXcorrDetector::update(const Observation& observation) {
  // Missed hops (a suspended detector, a gap in the source) break the filters' history.
  if (!std::isnan(last_t_) &&
      !(std::abs(observation.t - last_t_ - hop_seconds_) <= 0.5 * hop_seconds_)) {
    restart_filters();
  }
  last_t_ = observation.t;
  const std::span<const double> a = use_p2_alone_ ? observation.p2_samples : observation.p1_samples;
  const std::span<const double> b = observation.p2_samples;
  bool complete = !a.empty() && (!correlation_ || b.size() == a.size());
  if (!complete) restart_filters();
  HopSums sums;
  bool primed_throughout = true;
  for (std::size_t i = 0; complete && i < a.size(); ++i) {
    const double va = a[i];
    const double vb = correlation_ ? b[i] : 0.0;
    if (std::isnan(va) || std::isnan(vb)) {
      restart_filters();
      complete = false;
      break;
    }
    a_.push(va);
    if (correlation_) b_.push(vb);
    if (primed_ < kTaps) ++primed_;
    if (primed_ < kTaps) {
      primed_throughout = false;
      continue;
    }
    const double da = dot(level2_, a_.newest());
    if (correlation_) {
      const double db = dot(level2_, b_.newest());
      sums.aa += da * da;
      sums.bb += db * db;
      sums.ab += da * db;
    } else {
      const double d1 = dot(level1_, a_.newest());
      const double d3 = dot(level3_, a_.newest());
      sums.aa += da * da;
      sums.e1 += d1 * d1;
      sums.e3 += d3 * d3;
    }
  }
  // A hop counts only when every one of its samples had a primed filter.
  if (complete && primed_throughout) hops_.push(sums);
  const double value = complete ? feature() : kMissing;
  // A leak raises the correlation (less antiphase) and lowers the band ratio.
  const double oriented = correlation_ ? -value : value;
  // The correlation hardly moves with the oil (about 1/30 of its block spread per kelvin) and the
  // drift reference follows what does. With `temp` the test would fit a temperature coefficient
  // on what learning saw and stop following the slope: in warm-ups that learned on the steepest
  // warming that raised false alarms (2 in 0.9 h, docs/detection.md). So `temp` is not used
  // (FeaturePhysics::uses_temperature).
  const FeatureTest::Verdict verdict =
      test_.update(observation, std::isnan(value) ? kMissing : as_test_value(oriented));
  Decision decision;
  decision.learning = verdict.learning;
  decision.learning_hops_left = verdict.learning_hops_left;
  decision.score = verdict.score;
  // For the operator: the paper's index of the chamber, not the feature's scale.
  decision.index = use_p2_alone_ ? observation.index_p2 : observation.index_p1;
  decision.judge_by_score();
  verdict.apply_to(decision);
  return decision;
}

DetectorState DetailXcorrDetector::export_state() const {
  DetectorState state(std::string(name()), kStateVersion);
  test_.save(state, "test");
  auto history = [](const History& h) {
    return std::vector<double>(h.newest(), h.newest() + kTaps);
  };
  state.put("history_a", history(a_));
  state.put("history_b", history(b_));
  state.put_count("primed", primed_);
  save_ring(state, "hops", hops_, kHopFields);
  state.put("last_t", last_t_);
  return state;
}

void DetailXcorrDetector::import_state(const DetectorState& saved) {
  import_detector_state(*this, saved, kStateVersion, [this](const DetectorState& state) {
    test_.restore(state, "test");
    const auto& history_a = state.get_list("history_a");
    const auto& history_b = state.get_list("history_b");
    if (history_a.size() != kTaps || history_b.size() != kTaps) {
      throw StateError("filter history does not fit this configuration");
    }
    const std::size_t primed = state.get_count("primed");
    if (primed > kTaps) throw StateError("filter position out of range");
    a_ = History{};
    b_ = History{};
    for (std::size_t i = 0; i < kTaps; ++i) {
      a_.push(history_a[i]);
      b_.push(history_b[i]);
    }
    primed_ = primed;
    restore_ring(state, "hops", hops_, kHopFields);
    last_t_ = state.get("last_t");
  });
}

}  // namespace leakmon::detect
