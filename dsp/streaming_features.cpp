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
#include "dsp/incremental_plan.hpp"
#include "dsp/interleaved_kernels.hpp"
#include "dsp/row_history.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

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
      decimate_rows_right_end(right_real + (2 * l.clean_hi + l.dec.phase - right_first) * channels,
                              right_count, channels, l.filter, l.dec, l.clean_hi,
                              right_out[j].data());
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

  void build_extension_recipe(std::size_t j) {
    const LevelPlan& l = levels[j];
    append_extension_slots(l, params.mode, left_buf[j].data() + l.dec.left_ext * channels,
                           right_buf[j].data(), channels, extension);
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
