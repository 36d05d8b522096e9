// The arithmetic kernels of StreamingFeatures over channel-interleaved rows (row k holds
// channel c at [k * channels + c]): decimating convolution and sums of squares. What runs in
// parallel is independent sums (channels, or outputs of a single channel) so that the loops
// vectorise and no addition waits on another; each single sum keeps the order of the batch
// transform in dsp/dwt.cpp.
#pragma once

#include <cstddef>
#include <span>

namespace leakmon::dsp {

// Channels [first, first + B) of decimate_rows, B at a time, with the B running sums in
// registers.
template <std::size_t B>
void decimate_channel_block(const double* newest, std::size_t count, std::size_t channels,
                            std::span<const double> filter, double* __restrict__ out,
                            std::size_t first) {
  for (std::size_t k = 0; k < count; ++k) {
    double sum[B] = {};
    const double* in = newest + 2 * k * channels + first;
    for (std::size_t f = 0; f < filter.size(); ++f) {
      const double tap = filter[f];
      const double* __restrict__ row = in - static_cast<std::ptrdiff_t>(f * channels);
#pragma GCC unroll 8
      for (std::size_t b = 0; b < B; ++b) sum[b] += tap * row[b];
    }
    for (std::size_t b = 0; b < B; ++b) out[k * channels + first + b] = sum[b];
  }
}

// One channel: outputs [0, B) of decimate_rows, B at a time, with the B running sums in
// registers.
template <std::size_t B>
void decimate_output_block(const double* newest, std::span<const double> filter,
                           double* __restrict__ out) {
  double sum[B] = {};
  for (std::size_t f = 0; f < filter.size(); ++f) {
    const double tap = filter[f];
    const double* __restrict__ src = newest - static_cast<std::ptrdiff_t>(f);
#pragma GCC unroll 8
    for (std::size_t b = 0; b < B; ++b) sum[b] += tap * src[2 * b];
  }
  for (std::size_t b = 0; b < B; ++b) out[b] = sum[b];
}

// out[k*C + c] = sum_f filter[f] * newest[(2k - f) * C + c] for k < count: `count` decimated
// outputs of C interleaved channels. Each sum runs over f in order from 0.0, as dsp::decimate
// does, so both give the same bits; what runs in parallel is independent sums (channels, or
// outputs of a single channel), so the loops vectorise and no addition waits on another.
inline void decimate_rows(const double* newest, std::size_t count, std::size_t channels,
                          std::span<const double> filter, double* __restrict__ out) {
  if (channels == 1) {
    constexpr std::size_t kOutputs = 8;
    std::size_t k = 0;
    for (; k + kOutputs <= count; k += kOutputs) {
      decimate_output_block<kOutputs>(newest + 2 * k, filter, out + k);
    }
    if (k + 4 <= count) {
      decimate_output_block<4>(newest + 2 * k, filter, out + k);
      k += 4;
    }
    if (k + 2 <= count) {
      decimate_output_block<2>(newest + 2 * k, filter, out + k);
      k += 2;
    }
    if (k < count) decimate_output_block<1>(newest + 2 * k, filter, out + k);
    return;
  }
  constexpr std::size_t kBlock = 8;
  std::size_t c = 0;
  for (; c + kBlock <= channels; c += kBlock) {
    decimate_channel_block<kBlock>(newest, count, channels, filter, out, c);
  }
  for (; c < channels; ++c) decimate_channel_block<1>(newest, count, channels, filter, out, c);
}

inline void add_squares(const double* rows, std::size_t count, std::size_t channels,
                        double* energy) {
  if (channels == 1) {
    // Four partial sums: one running sum would wait on each addition's latency.
    double lane[4] = {0.0, 0.0, 0.0, 0.0};
    std::size_t k = 0;
    for (; k + 4 <= count; k += 4) {
      for (std::size_t i = 0; i < 4; ++i) lane[i] += rows[k + i] * rows[k + i];
    }
    for (; k < count; ++k) lane[k % 4] += rows[k] * rows[k];
    energy[0] += (lane[0] + lane[1]) + (lane[2] + lane[3]);
    return;
  }
  // Eight channels at a time, their sums in registers; each channel still sums in row order.
  constexpr std::size_t kBlock = 8;
  std::size_t c = 0;
  for (; c + kBlock <= channels; c += kBlock) {
    double sum[kBlock];
    for (std::size_t b = 0; b < kBlock; ++b) sum[b] = energy[c + b];
    for (std::size_t k = 0; k < count; ++k) {
      const double* __restrict__ row = rows + k * channels + c;
#pragma GCC unroll 8
      for (std::size_t b = 0; b < kBlock; ++b) sum[b] += row[b] * row[b];
    }
    for (std::size_t b = 0; b < kBlock; ++b) energy[c + b] = sum[b];
  }
  for (; c < channels; ++c) {
    for (std::size_t k = 0; k < count; ++k)
      energy[c] += rows[k * channels + c] * rows[k * channels + c];
  }
}

}  // namespace leakmon::dsp
