#include "dsp/streaming_features.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "dsp/dwt.hpp"
#include "dsp/extension.hpp"
#include "dsp/interleaved_kernels.hpp"
#include "dsp/row_history.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

void validate(const FeatureParams& params) {
  if (!has_wavelet(params.wavelet)) {
    throw std::invalid_argument(fmt::format(
        "wavelet: unknown wavelet '{}' (offered: haar, db1..db20, sym2..sym20, coif1..coif5)",
        params.wavelet));
  }
  const std::size_t taps = wavelet(params.wavelet).filter_length();
  if (params.step == 0) throw std::invalid_argument("step: must be at least 1 sample, got 0");
  if (params.window < taps) {
    throw std::invalid_argument(
        fmt::format("window: {} samples is shorter than the {} filter ({} taps)", params.window,
                    params.wavelet, taps));
  }
  if (params.level < 1) {
    throw std::invalid_argument(fmt::format("level: must be at least 1, got {}", params.level));
  }
  const int max_level = dwt_max_level(params.window, taps);
  if (params.level > max_level) {
    throw std::invalid_argument(fmt::format(
        "level: {} is above the maximum level {} for a {}-sample window with {} ({} taps); every "
        "coefficient would depend on the boundary extension",
        params.level, max_level, params.window, params.wavelet, taps));
  }
  if (mode_name(params.mode) == "unknown") {
    throw std::invalid_argument(
        fmt::format("mode: value {} is not an extension mode", static_cast<int>(params.mode)));
  }
}

namespace {

DetailFeature feature_from_energy(double energy, std::size_t count) {
  return {std::sqrt(energy / static_cast<double>(count)), energy, true};
}

// One level of the incremental scheme. At window start s (a multiple of 2^level), output k of
// this level equals the coefficient at absolute position (s >> level) + k of the transform of
// the unbounded stream whenever its taps read no extended input: that "clean" range
// [clean_lo, clean_hi) is computed once per position and kept in a RowHistory. Only the
// boundary outputs, which read the mode's extension, are recomputed per window, from copies of
// the input's two edges.
struct LevelPlan {
  Decimation dec;
  std::span<const double> filter;  // dec_lo below the feature level, dec_hi at it
  std::size_t clean_lo = 0;
  std::size_t clean_hi = 0;
  std::size_t edge_left = 0;   // input values a[0, edge_left) held for the left boundary
  std::size_t edge_right = 0;  // input values a[n_in - edge_right, n_in) for the right one
};

// One extension value of one edge buffer, resolved at construction so that the per-window work
// is a copy or a short formula over the channels: the same values, by the same arithmetic, as
// extend_before_start/extend_after_end (the streaming-equals-batch tests check every mode).
struct ExtensionSlot {
  enum class Kind { zero, copy, negate, smooth, antireflect } kind = Kind::zero;
  double* dst = nullptr;
  const double* a = nullptr;  // copy/negate: source; smooth/antireflect: the edge value
  const double* b = nullptr;  // smooth: the value next to the edge; antireflect: the mirrored one
  double factor = 0.0;        // smooth: distance from the edge

  void fill(std::size_t channels) const noexcept {
    switch (kind) {
      case Kind::zero:
        for (std::size_t c = 0; c < channels; ++c) dst[c] = 0.0;
        break;
      case Kind::copy:
        for (std::size_t c = 0; c < channels; ++c) dst[c] = a[c];
        break;
      case Kind::negate:
        for (std::size_t c = 0; c < channels; ++c) dst[c] = -a[c];
        break;
      case Kind::smooth:
        for (std::size_t c = 0; c < channels; ++c) dst[c] = a[c] + factor * (a[c] - b[c]);
        break;
      case Kind::antireflect:
        for (std::size_t c = 0; c < channels; ++c) dst[c] = a[c] - (b[c] - a[c]);
        break;
    }
  }
};

std::optional<std::vector<LevelPlan>> plan_incremental(const FeatureParams& params,
                                                       const Wavelet& w) {
  const std::size_t taps = w.filter_length();
  const std::size_t decimation_period = std::size_t{1} << params.level;
  if (params.step % decimation_period != 0) return std::nullopt;  // phase would change
  std::vector<LevelPlan> plan;
  std::size_t n_in = params.window;
  std::size_t prev_lo = 0;
  std::size_t prev_hi = params.window;
  for (int level = 1; level <= params.level; ++level) {
    LevelPlan p;
    p.dec = decimation(n_in, taps, params.mode);
    p.filter = level < params.level ? w.dec_lo : w.dec_hi;
    if (n_in < taps) return std::nullopt;  // extension would reflect more than once
    const auto phase = static_cast<long long>(p.dec.phase);
    const long long lowest = static_cast<long long>(prev_lo + taps - 1) - phase;
    p.clean_lo = lowest <= 0 ? 0 : static_cast<std::size_t>((lowest + 1) / 2);
    const long long highest = static_cast<long long>(prev_hi) - 1 - phase;
    if (highest < 0) return std::nullopt;
    p.clean_hi = std::min(p.dec.n_out, static_cast<std::size_t>(highest / 2 + 1));
    if (p.clean_lo >= p.clean_hi) return std::nullopt;
    const std::size_t left_reads = p.clean_lo == 0 ? 0 : 2 * (p.clean_lo - 1) + p.dec.phase + 1;
    const long long first_right_read =
        static_cast<long long>(2 * p.clean_hi + p.dec.phase) - static_cast<long long>(taps - 1);
    const std::size_t right_reads =
        first_right_read >= static_cast<long long>(n_in)
            ? 0
            : n_in - static_cast<std::size_t>(std::max(0LL, first_right_read));
    p.edge_left = std::max(taps, left_reads);
    p.edge_right = std::max(taps, right_reads);
    if (p.edge_left > prev_hi || p.edge_right > n_in - prev_lo || p.edge_left > n_in ||
        p.edge_right > n_in) {
      return std::nullopt;
    }
    plan.push_back(p);
    prev_lo = p.clean_lo;
    prev_hi = p.clean_hi;
    n_in = p.dec.n_out;
  }
  return plan;
}

}  // namespace

struct StreamingFeatures::Engine {
  Engine(const FeatureParams& p, std::size_t channel_count)
      : params(p), channels(channel_count), w(wavelet(p.wavelet)) {
    if (channels == 0) throw std::invalid_argument("channels: must be at least 1, got 0");
    latest.resize(channels);
    energy.resize(channels);
    gap_end.resize(channels);
    samples = RowHistory(2 * params.window + params.step, channels);
    if (auto plan = plan_incremental(params, w)) {
      levels = std::move(*plan);
      for (std::size_t j = 0; j < levels.size(); ++j) {
        const LevelPlan& l = levels[j];
        const std::size_t clean = l.clean_hi - l.clean_lo;
        coeffs.emplace_back(2 * clean + (params.step >> (j + 1)) + w.filter_length(), channels);
        left_buf.emplace_back((l.dec.left_ext + l.edge_left) * channels);
        right_buf.emplace_back((l.edge_right + l.dec.right_ext) * channels);
        left_out.emplace_back(l.clean_lo * channels);
        right_out.emplace_back((l.dec.n_out - l.clean_hi) * channels);
      }
      for (std::size_t j = 0; j < levels.size(); ++j) build_extension_recipe(j);
    } else {
      transform.emplace(params.window, w, params.mode, params.level);
      window_buf.resize(params.window);
    }
    reset();
  }

  void reset() noexcept {
    seen = 0;
    next_start = 0;
    gaps_checked = 0;
    samples.restart(0);
    for (auto& h : coeffs) h.restart(0);
    std::fill(gap_end.begin(), gap_end.end(), 0);
    std::fill(latest.begin(), latest.end(), DetailFeature{});
  }

  // Per sample only a copy into the history; the NaN check and all arithmetic run once per
  // window, over the samples that arrived since the previous one.
  bool push(std::span<const double> sample) noexcept {
    assert(sample.size() == channels);
    const std::uint64_t t = seen++;
    if (t < next_start) return false;  // step > window: this sample is in no window
    if (samples.end() != t) samples.restart(t);
    double* row = samples.append();
    for (std::size_t c = 0; c < channels; ++c) row[c] = sample[c];
    if (seen != next_start + params.window) return false;
    const std::uint64_t start = next_start;
    note_gaps(std::max(gaps_checked, start), seen);
    if (levels.empty()) {
      recompute_window(start);
    } else {
      update_window(start);
    }
    for (std::size_t c = 0; c < channels; ++c) {
      latest[c] =
          gap_end[c] > start ? DetailFeature{} : feature_from_energy(energy[c], detail_count());
    }
    next_start += params.step;
    samples.release_before(next_start);
    return true;
  }

  // gap_end[c] = one past the last NaN of channel c among samples [first, end) (in the history);
  // samples before the window's start cannot invalidate it, so they need no look.
  void note_gaps(std::uint64_t first, std::uint64_t end) noexcept {
    const double* rows = samples.row(first);
    for (std::uint64_t t = first; t < end; ++t, rows += channels) {
      for (std::size_t c = 0; c < channels; ++c) {
        if (std::isnan(rows[c])) gap_end[c] = t + 1;
      }
    }
    gaps_checked = end;
  }

  std::size_t detail_count() const noexcept {
    return levels.empty() ? transform->detail_len() : levels.back().dec.n_out;
  }

  // Fallback: the whole window through the batch transform, one channel at a time.
  void recompute_window(std::uint64_t start) noexcept {
    for (std::size_t c = 0; c < channels; ++c) {
      for (std::size_t i = 0; i < params.window; ++i) window_buf[i] = samples.row(start + i)[c];
      double sum = 0.0;
      for (double d : transform->detail(window_buf)) sum += d * d;
      energy[c] = sum;
    }
  }

  void update_window(std::uint64_t start) noexcept {
    const std::size_t row_bytes = channels * sizeof(double);
    for (std::size_t j = 0; j < levels.size(); ++j) {
      const LevelPlan& l = levels[j];
      const std::size_t level = j + 1;
      const RowHistory& input = j == 0 ? samples : coeffs[j - 1];
      RowHistory& output = coeffs[j];
      const std::uint64_t in_origin = start >> j;
      const std::uint64_t out_origin = start >> level;

      // New clean coefficients: those the previous window did not have.
      const std::uint64_t first = out_origin + l.clean_lo;
      const std::uint64_t last = out_origin + l.clean_hi;
      if (output.end() < first || output.empty()) output.restart(first);
      if (last > output.end()) {
        const std::uint64_t from = output.end();
        const std::size_t count = last - from;
        double* out = output.append(count);
        decimate_rows(input.row(2 * from + l.dec.phase), count, channels, l.filter, out);
      }

      // The input's edges: boundary outputs of the level below, or clean history, or samples.
      const std::size_t n_in = l.dec.n_in;
      double* left_real = left_buf[j].data() + l.dec.left_ext * channels;
      double* right_real = right_buf[j].data();
      const std::size_t right_first = n_in - l.edge_right;
      if (j == 0) {
        std::memcpy(left_real, samples.row(start), l.edge_left * row_bytes);
        std::memcpy(right_real, samples.row(start + right_first), l.edge_right * row_bytes);
      } else {
        const LevelPlan& below = levels[j - 1];
        std::memcpy(left_real, left_out[j - 1].data(), below.clean_lo * row_bytes);
        std::memcpy(left_real + below.clean_lo * channels, input.row(in_origin + below.clean_lo),
                    (l.edge_left - below.clean_lo) * row_bytes);
        std::memcpy(right_real, input.row(in_origin + right_first),
                    (below.clean_hi - right_first) * row_bytes);
        std::memcpy(right_real + (below.clean_hi - right_first) * channels, right_out[j - 1].data(),
                    (n_in - below.clean_hi) * row_bytes);
      }
      for (std::size_t e = j == 0 ? 0 : extension_end[j - 1]; e < extension_end[j]; ++e) {
        extension[e].fill(channels);
      }

      const std::size_t right_count = l.dec.n_out - l.clean_hi;
      decimate_rows(left_buf[j].data() + (l.dec.left_ext + l.dec.phase) * channels, l.clean_lo,
                    channels, l.filter, left_out[j].data());
      decimate_rows(right_real + (2 * l.clean_hi + l.dec.phase - right_first) * channels,
                    right_count, channels, l.filter, right_out[j].data());
    }

    const LevelPlan& top = levels.back();
    const std::uint64_t origin = start >> levels.size();
    std::fill(energy.begin(), energy.end(), 0.0);
    add_squares(left_out.back().data(), top.clean_lo, channels, energy.data());
    add_squares(coeffs.back().row(origin + top.clean_lo), top.clean_hi - top.clean_lo, channels,
                energy.data());
    add_squares(right_out.back().data(), top.dec.n_out - top.clean_hi, channels, energy.data());
    // Only now, after the level above and the energy sum have read them, may each level drop the
    // coefficients that the next window no longer needs.
    for (std::size_t j = 0; j < levels.size(); ++j) {
      coeffs[j].release_before(((start + params.step) >> (j + 1)) + levels[j].clean_lo);
    }
  }

  // Resolves every extension value of level j's edge buffers to an ExtensionSlot. The plan
  // guarantees a single reflection, so every value reads the edges' real rows.
  void build_extension_recipe(std::size_t j) {
    const LevelPlan& l = levels[j];
    const std::size_t n = l.dec.n_in;
    const std::size_t right_first = n - l.edge_right;
    double* left_real = left_buf[j].data() + l.dec.left_ext * channels;
    double* right_real = right_buf[j].data();
    auto row = [&](std::size_t i) -> const double* {
      if (i < l.edge_left) return left_real + i * channels;
      if (i < right_first) throw std::logic_error("extension reads outside the edge buffers");
      return right_real + (i - right_first) * channels;
    };
    // For the modes that only pick (and maybe negate) a sample, probe which one: a[i] = i + 1.
    auto probe = [](std::size_t i) { return static_cast<double>(i) + 1.0; };
    auto slot = [&](double* dst, std::size_t m, bool left) {
      ExtensionSlot e;
      e.dst = dst;
      const std::size_t edge = left ? 0 : n - 1;
      const std::size_t inward = left ? edge + 1 : edge - 1;
      switch (params.mode) {
        case Mode::zero:
          break;
        case Mode::smooth:
          e = {ExtensionSlot::Kind::smooth, dst, row(edge), row(inward), static_cast<double>(m)};
          break;
        case Mode::antireflect:
          e = {ExtensionSlot::Kind::antireflect, dst, row(edge), row(left ? edge + m : edge - m),
               0.0};
          break;
        default: {
          const double v = left ? extend_before_start(params.mode, n, m, probe)
                                : extend_after_end(params.mode, n, m, probe);
          e.kind = v < 0 ? ExtensionSlot::Kind::negate : ExtensionSlot::Kind::copy;
          e.a = row(static_cast<std::size_t>(std::abs(v)) - 1);
        }
      }
      extension.push_back(e);
    };
    for (std::size_t m = 1; m <= l.dec.left_ext; ++m) {
      slot(left_real - m * channels, m, true);
    }
    for (std::size_t m = 1; m <= l.dec.right_ext; ++m) {
      slot(right_real + (l.edge_right - 1 + m) * channels, m, false);
    }
    extension_end.push_back(extension.size());
  }

  FeatureParams params;
  std::size_t channels;
  const Wavelet& w;
  std::vector<LevelPlan> levels;  // empty: recompute every window
  RowHistory samples;
  std::vector<RowHistory> coeffs;  // per level: its clean coefficients
  std::vector<std::vector<double>> left_buf, right_buf, left_out, right_out;
  std::vector<ExtensionSlot> extension;    // all levels' extension values, level by level
  std::vector<std::size_t> extension_end;  // per level: one past its last slot
  std::optional<DetailTransform> transform;
  std::vector<double> window_buf;
  std::vector<double> energy;
  std::vector<DetailFeature> latest;
  std::vector<std::uint64_t> gap_end;  // per channel: one past its last NaN sample
  std::uint64_t gaps_checked = 0;      // samples before it have been looked at for NaN
  std::uint64_t seen = 0;
  std::uint64_t next_start = 0;
};

StreamingFeatures::StreamingFeatures(const FeatureParams& params, std::size_t channels)
    : engine_(nullptr) {
  validate(params);
  engine_ = new Engine(params, channels);
}

StreamingFeatures::~StreamingFeatures() { delete engine_; }

StreamingFeatures::StreamingFeatures(StreamingFeatures&& other) noexcept
    : engine_(std::exchange(other.engine_, nullptr)) {}

StreamingFeatures& StreamingFeatures::operator=(StreamingFeatures&& other) noexcept {
  if (this != &other) {
    delete engine_;
    engine_ = std::exchange(other.engine_, nullptr);
  }
  return *this;
}

bool StreamingFeatures::push(std::span<const double> sample) noexcept {
  return engine_->push(sample);
}
std::span<const DetailFeature> StreamingFeatures::latest() const noexcept {
  return engine_->latest;
}
std::uint64_t StreamingFeatures::samples_seen() const noexcept { return engine_->seen; }
void StreamingFeatures::reset() noexcept { engine_->reset(); }
const FeatureParams& StreamingFeatures::params() const noexcept { return engine_->params; }
std::size_t StreamingFeatures::channels() const noexcept { return engine_->channels; }
bool StreamingFeatures::incremental() const noexcept { return !engine_->levels.empty(); }

std::vector<DetailFeature> sliding_detail_features(std::span<const double> signal,
                                                   const FeatureParams& params) {
  validate(params);
  std::vector<DetailFeature> features;
  if (signal.size() < params.window) return features;
  DetailTransform transform(params.window, wavelet(params.wavelet), params.mode, params.level);
  for (std::size_t start = 0; start + params.window <= signal.size(); start += params.step) {
    const auto window = signal.subspan(start, params.window);
    if (std::any_of(window.begin(), window.end(), [](double v) { return std::isnan(v); })) {
      features.emplace_back();
      continue;
    }
    double energy = 0.0;
    for (double d : transform.detail(window)) energy += d * d;
    features.push_back(feature_from_energy(energy, transform.detail_len()));
  }
  return features;
}

}  // namespace leakmon::dsp
