#include "dsp/boundary_map.hpp"

#include <algorithm>

#include "dsp/dwt.hpp"
#include "dsp/interleaved_kernels.hpp"

namespace leakmon::dsp {

namespace {
constexpr std::size_t kPad = 8;  // dot_multiple_of_8 takes one channel 8 rows at a time
}

BoundaryMap::BoundaryMap(std::size_t window, const Wavelet& wavelet, Mode mode, int level,
                         std::size_t clean_lo, std::size_t clean_hi, std::size_t channels)
    : window_(window), channels_(channels) {
  DetailTransform transform(window, wavelet, mode, level);
  const std::size_t n_out = transform.detail_len();
  std::vector<std::size_t> outputs;
  for (std::size_t k = 0; k < clean_lo; ++k) outputs.push_back(k);
  for (std::size_t k = clean_hi; k < n_out; ++k) outputs.push_back(k);
  left_count_ = clean_lo;

  // response[r * window + i]: boundary output r for a unit impulse at sample i.
  std::vector<double> response(outputs.size() * window);
  std::vector<double> impulse(window, 0.0);
  for (std::size_t i = 0; i < window; ++i) {
    impulse[i] = 1.0;
    const auto detail = transform.detail(impulse);
    for (std::size_t r = 0; r < outputs.size(); ++r) response[r * window + i] = detail[outputs[r]];
    impulse[i] = 0.0;
  }
  const std::vector<double> ones(window, 1.0);
  const auto level_response = transform.detail(ones);
  for (std::size_t k : outputs) level_gain_.push_back(level_response[k]);

  // Each row's nonzero span in either half of the window.
  const std::size_t half = window / 2;
  struct Span {
    std::size_t first, end;
  };
  auto nonzero = [](const double* weights, std::size_t first, std::size_t end) {
    while (first < end && weights[first] == 0.0) ++first;
    while (end > first && weights[end - 1] == 0.0) --end;
    return Span{first, end};
  };
  std::vector<Span> lows, highs;
  high_begin_ = window;
  for (std::size_t r = 0; r < outputs.size(); ++r) {
    lows.push_back(nonzero(response.data() + r * window, 0, half));
    highs.push_back(nonzero(response.data() + r * window, half, window));
    if (lows.back().end > lows.back().first) low_end_ = std::max(low_end_, lows.back().end);
    if (highs.back().end > highs.back().first) {
      high_begin_ = std::min(high_begin_, highs.back().first);
    }
  }
  const std::size_t high_origin = low_end_ + kPad;  // deviation_ row of sample high_begin_
  deviation_.assign((high_origin + (window - high_begin_) + kPad) * channels, 0.0);

  auto segment = [&](const double* weights, Span span, std::size_t row_of_first) {
    Segment s;
    s.first = row_of_first;
    s.length = span.end - span.first;
    s.padded = (s.length + kPad - 1) / kPad * kPad;
    s.weights = weights_.size();
    weights_.insert(weights_.end(), weights + span.first, weights + span.end);
    weights_.resize(s.weights + s.padded, 0.0);
    return s;
  };
  for (std::size_t r = 0; r < outputs.size(); ++r) {
    const double* weights = response.data() + r * window;
    Row row;
    row.low = segment(weights, lows[r], lows[r].first);
    row.high = segment(weights, highs[r], high_origin + highs[r].first - high_begin_);
    rows_.push_back(row);
  }
}

// One channel: dense dot products over contiguous weights, the whole map in a few hundred
// vector multiply-adds. Built twice (baseline SSE2 and AVX2, picked at load time by the CPU):
// AVX2 doubles the vector width; no FMA, so the rounding is the same in both.
__attribute__((target_clones("avx2", "default"))) void BoundaryMap::apply_one_channel(
    const double* window, double* out) noexcept {
  const double reference = window[0];
  double* deviation = deviation_.data();
  for (std::size_t i = 0; i < low_end_; ++i) deviation[i] = window[i] - reference;
  double* high = deviation + low_end_ + kPad;
  for (std::size_t i = high_begin_; i < window_; ++i) high[i - high_begin_] = window[i] - reference;
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    const Segment& low = rows_[r].low;
    const Segment& hi = rows_[r].high;
    const double sum =
        dot_multiple_of_8(weights_.data() + low.weights, deviation + low.first, low.padded) +
        dot_multiple_of_8(weights_.data() + hi.weights, deviation + hi.first, hi.padded);
    out[r] = sum + level_gain_[r] * reference;
  }
}

void BoundaryMap::apply(const double* window_rows, double* out) noexcept {
  if (channels_ == 1) {
    apply_one_channel(window_rows, out);
    return;
  }
  // Many channels: the loops run over the channels of a row, eight at a time.
  const std::size_t channels = channels_;
  // The window's first sample is each channel's reference level.
  const double* reference = window_rows;
  auto deviate = [&](std::size_t first_sample, std::size_t end_sample, double* dst) {
    for (std::size_t i = first_sample; i < end_sample; ++i) {
      const double* src = window_rows + i * channels;
      for (std::size_t c = 0; c < channels; ++c) *dst++ = src[c] - reference[c];
    }
  };
  deviate(high_begin_, window_, deviation_.data() + (low_end_ + kPad) * channels);
  deviate(0, low_end_, deviation_.data());
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    double* sums = out + r * channels;
    for (std::size_t c = 0; c < channels; ++c) sums[c] = 0.0;
    for (const Segment* s : {&rows_[r].low, &rows_[r].high}) {
      if (s->length == 0) continue;
      add_weighted_rows(weights_.data() + s->weights, s->length,
                        deviation_.data() + s->first * channels, channels, sums);
    }
    for (std::size_t c = 0; c < channels; ++c) sums[c] += level_gain_[r] * reference[c];
  }
}

}  // namespace leakmon::dsp
