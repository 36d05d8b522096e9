#include "detect/detail_xcorr_detector.hpp"

#include <algorithm>
#include <cmath>
#include <span>
#include <string>
#include <vector>

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

IndexCusumOptions test_options(const DetailXcorrOptions& o, bool correlation) {
  IndexCusumOptions test = o.test;
  // The feature is a ratio: the supply's and the oil's effects on the index's size cancel in it;
  // what is left of them the regression and the drift reference follow.
  test.supply_exponent = 0.0;
  test.temperature_prior = 0.0;
  const double design = correlation ? o.design_shift_correlation : o.design_shift_ratio;
  const double floor = correlation ? o.min_shift_correlation : o.min_shift_ratio;
  // The test looks for a drop of log(index) by -log(1 - design_drop); the "index" handed to it
  // is exp(feature), oriented so that a leak lowers it.
  test.design_drop = -std::expm1(-design);
  test.min_drop = -std::expm1(-floor);
  return test;
}

constexpr int kStateVersion = 1;

}  // namespace

DetailXcorrDetector::DetailXcorrDetector(const DetailXcorrOptions& options, double hop_seconds)
    : options_(options),
      hop_seconds_(hop_seconds),
      correlation_(options.test.use_p1 && options.test.use_p2),
      use_p2_alone_(!options.test.use_p1 && options.test.use_p2),
      test_(test_options(options, options.test.use_p1 && options.test.use_p2), hop_seconds) {
  options_.window_hops = std::clamp<std::size_t>(options_.window_hops, 1, kMaxWindowHops);
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
  hops_filled_ = 0;
  hop_next_ = 0;
}

void DetailXcorrDetector::reset() {
  restart_filters();
  a_ = History{};
  b_ = History{};
  hops_.fill(HopSums{});
  last_t_ = kMissing;
  test_.reset();
}

void DetailXcorrDetector::resume_after_gap() {
  restart_filters();
  last_t_ = kMissing;
  test_.resume_after_gap();
}

double DetailXcorrDetector::feature() const {
  if (hops_filled_ < options_.window_hops) return kMissing;
  HopSums total;
  // Oldest first, so that an imported state (stored oldest first) sums in the same order.
  for (std::size_t i = 0; i < options_.window_hops; ++i) {
    const HopSums& h = hops_[(hop_next_ + i) % options_.window_hops];
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
  if (complete && primed_throughout) {
    hops_[hop_next_] = sums;
    hop_next_ = (hop_next_ + 1) % options_.window_hops;
    if (hops_filled_ < options_.window_hops) ++hops_filled_;
  }
  const double value = complete ? feature() : kMissing;

  Observation inner = observation;
  const double oriented = correlation_ ? -value : value;
  const double index = std::isnan(value) ? kMissing : std::exp(oriented);
  inner.index_p1 = index;
  inner.index_p2 = index;
  // The correlation hardly moves with the oil (about 1/30 of its block spread per kelvin) and the
  // drift reference follows what does. With `temp` the test would fit a temperature coefficient
  // on what learning saw and stop following the slope: in warm-ups that learned on the steepest
  // warming that raised false alarms (2 in 0.9 h, docs/detection.md). So `temp` is not used.
  inner.temp = kMissing;
  Decision decision = test_.update(inner);
  // For the operator: the paper's index of the chamber, not the feature's scale.
  decision.index = use_p2_alone_ ? observation.index_p2 : observation.index_p1;
  decision.baseline = kMissing;
  return decision;
}

DetectorState DetailXcorrDetector::export_state() const {
  DetectorState state(std::string(name()), kStateVersion);
  state.put_nested("test", test_.export_state());
  auto history = [](const History& h) {
    return std::vector<double>(h.newest(), h.newest() + kTaps);
  };
  state.put("history_a", history(a_));
  state.put("history_b", history(b_));
  state.put_count("primed", primed_);
  std::vector<double> hops;
  for (std::size_t i = 0; i < options_.window_hops; ++i) {
    const HopSums& h = hops_[(hop_next_ + i) % options_.window_hops];  // oldest first
    hops.insert(hops.end(), {h.aa, h.bb, h.ab, h.e1, h.e3});
  }
  state.put("hops", hops);
  state.put_count("hops_filled", hops_filled_);
  state.put("last_t", last_t_);
  return state;
}

void DetailXcorrDetector::import_state(const DetectorState& state) {
  try {
    state.expect(name(), kStateVersion);
    test_.import_state(state.get_nested("test"));
    const auto& history_a = state.get_list("history_a");
    const auto& history_b = state.get_list("history_b");
    const auto& hops = state.get_list("hops");
    if (history_a.size() != kTaps || history_b.size() != kTaps ||
        hops.size() != 5 * options_.window_hops) {
      throw StateError("detail_xcorr: filter history does not fit this configuration");
    }
    const std::size_t primed = state.get_count("primed");
    const std::size_t filled = state.get_count("hops_filled");
    if (primed > kTaps || filled > options_.window_hops) {
      throw StateError("detail_xcorr: filter position out of range");
    }
    a_ = History{};
    b_ = History{};
    for (std::size_t i = 0; i < kTaps; ++i) {
      a_.push(history_a[i]);
      b_.push(history_b[i]);
    }
    for (std::size_t i = 0; i < options_.window_hops; ++i) {
      hops_[i] = {hops[5 * i], hops[5 * i + 1], hops[5 * i + 2], hops[5 * i + 3], hops[5 * i + 4]};
    }
    hop_next_ = 0;
    primed_ = primed;
    hops_filled_ = filled;
    last_t_ = state.get("last_t");
  } catch (...) {
    reset();
    throw;
  }
}

}  // namespace leakmon::detect
