// The window's boundary detail coefficients (those whose computation reads the extension mode at
// some level) as one linear map straight from the window's samples. Every mode is linear in the
// signal, so composing extension, the low-pass stages and the final high-pass gives, for each
// boundary coefficient, one row of weights; a row is nonzero only near the edges (near both for
// the periodic modes), so it is kept as two dense segments, one per half of the window.
// The weights are read off the batch transform itself (the response to each unit impulse), so
// the map needs no knowledge of any mode's rules. The values differ from the batch transform
// only by rounding order; the map weighs each sample's deviation from the window's first sample
// (and adds that level times the response to a constant) so that a large pressure level adds no
// rounding of its own.
#pragma once

#include <cstddef>
#include <vector>

#include "dsp/mode.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

class BoundaryMap {
 public:
  BoundaryMap() = default;
  // Boundary outputs: detail coefficients [0, clean_lo) and [clean_hi, n_out) of the
  // level-`level` transform of a `window`-sample window, for `channels` interleaved channels.
  BoundaryMap(std::size_t window, const Wavelet& wavelet, Mode mode, int level,
              std::size_t clean_lo, std::size_t clean_hi, std::size_t channels);

  std::size_t left_count() const noexcept { return left_count_; }
  std::size_t right_count() const noexcept { return rows_.size() - left_count_; }

  // out[r * channels + c]: boundary output r (left ones, then right ones) of channel c, from the
  // window's rows (window_rows[i * channels + c] = sample i of channel c). Allocation-free.
  void apply(const double* window_rows, double* out) noexcept;

 private:
  void apply_one_channel(const double* window, double* out) noexcept;

  struct Segment {
    std::size_t first = 0;    // first row in deviation_
    std::size_t length = 0;   // rows (and weights) up to the last nonzero weight
    std::size_t padded = 0;   // length rounded up to a multiple of 8 (zero weights)
    std::size_t weights = 0;  // offset of its weights in weights_
  };
  struct Row {
    Segment low, high;  // within the first and the second half of the window
  };
  std::size_t window_ = 0;
  std::size_t channels_ = 0;
  std::vector<Row> rows_;
  std::vector<double> weights_;
  std::vector<double> level_gain_;  // per row: its output for a constant signal of 1
  std::size_t left_count_ = 0;
  // The rows the map reads, minus the reference: samples [0, low_end_) then
  // [high_begin_, window), each region followed by 8 zero rows that padded segments may read.
  std::size_t low_end_ = 0;
  std::size_t high_begin_ = 0;
  std::vector<double> deviation_;
};

}  // namespace leakmon::dsp
