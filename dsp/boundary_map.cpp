#include "dsp/boundary_map.hpp"

#include <algorithm>

#include "dsp/dwt.hpp"
#include "dsp/interleaved_kernels.hpp"

namespace leakmon::dsp {

BoundaryMap::BoundaryMap(std::size_t window, const Wavelet& wavelet, Mode mode, int level,
                         std::size_t clean_lo, std::size_t clean_hi) {
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

  // The response to a constant: what each output adds per unit of the reference level.
  const std::vector<double> ones(window, 1.0);
  const auto level_response = transform.detail(ones);
  for (std::size_t k : outputs) level_gain_.push_back(level_response[k]);

  const std::size_t half = window / 2;
  auto segment = [&](const double* weights, std::size_t first, std::size_t end) {
    Segment s;
    while (first < end && weights[first] == 0.0) ++first;
    while (end > first && weights[end - 1] == 0.0) --end;
    s.first = first;
    s.length = end - first;
    s.weights = weights_.size();
    weights_.insert(weights_.end(), weights + first, weights + end);
    return s;
  };
  for (std::size_t r = 0; r < outputs.size(); ++r) {
    const double* weights = response.data() + r * window;
    Row row;
    row.low = segment(weights, 0, half);
    row.high = segment(weights, half, window);
    rows_.push_back(row);
  }
}

void BoundaryMap::apply(const double* window_rows, std::size_t channels,
                        double* out) const noexcept {
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    // The window's first sample is each channel's reference level.
    const double* reference = window_rows;
    double* sums = out + r * channels;
    std::fill(sums, sums + channels, 0.0);
    for (const Segment& s : {rows_[r].low, rows_[r].high}) {
      if (s.length == 0) continue;
      add_weighted_rows(weights_.data() + s.weights, s.length, window_rows + s.first * channels,
                        channels, reference, sums);
    }
    for (std::size_t c = 0; c < channels; ++c) sums[c] += level_gain_[r] * reference[c];
  }
}

}  // namespace leakmon::dsp
