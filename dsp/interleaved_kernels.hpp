// The arithmetic kernels of StreamingFeatures over channel-interleaved rows (row k holds
// channel c at [k * channels + c]): decimating convolution and sums of squares. What runs in
// parallel is independent sums (channels, or outputs of a single channel) so that the loops
// vectorise and no addition waits on another; each single sum keeps the order of the batch
// transform in dsp/dwt.cpp.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <span>

#include "dsp/dwt.hpp"

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

// One channel, outputs [0, 8) of decimate_rows with contiguous loads: for an even tap f the
// 8 outputs read x[P + 2b] and for tap f + 1 x[P - 1 + 2b] (P = newest - f); loading
// x[P - 1 .. P + 7) and unpacking the odd and even elements of each 128-bit half gives both,
// with the outputs in lanes (0, 2, 1, 3), (4, 6, 5, 7), put back in order at the store. Each
// lane still adds tap f, then f + 1, in ascending order: the same sum as decimate_output_block.
inline void decimate_8_outputs_paired(const double* newest, std::span<const double> filter,
                                      double* __restrict__ out) {
  using v4 = double __attribute__((vector_size(32)));
  v4 lo = {0.0, 0.0, 0.0, 0.0};
  v4 hi = {0.0, 0.0, 0.0, 0.0};
  for (std::size_t f = 0; f + 1 < filter.size(); f += 2) {
    const double* p = newest - static_cast<std::ptrdiff_t>(f) - 1;
    v4 a, b, c, d;  // x[P - 1 .. P + 15): 16 doubles, 4 vectors
    std::memcpy(&a, p, sizeof a);
    std::memcpy(&b, p + 4, sizeof b);
    std::memcpy(&c, p + 8, sizeof c);
    std::memcpy(&d, p + 12, sizeof d);
    const v4 even_lo = __builtin_shufflevector(a, b, 1, 5, 3, 7);  // tap f, outputs 0 2 1 3
    const v4 odd_lo = __builtin_shufflevector(a, b, 0, 4, 2, 6);   // tap f + 1
    const v4 even_hi = __builtin_shufflevector(c, d, 1, 5, 3, 7);
    const v4 odd_hi = __builtin_shufflevector(c, d, 0, 4, 2, 6);
    lo += filter[f] * even_lo;
    hi += filter[f] * even_hi;
    lo += filter[f + 1] * odd_lo;
    hi += filter[f + 1] * odd_hi;
  }
  const double ordered[8] = {lo[0], lo[2], lo[1], lo[3], hi[0], hi[2], hi[1], hi[3]};
  std::memcpy(out, ordered, sizeof ordered);
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

// Channels [first, first + B) of one output whose first `reversed` taps are summed from tap
// reversed - 1 down to 0 and the others ascending (Decimation::reversed_taps).
template <std::size_t B>
void decimate_reversed_head(const double* newest, std::size_t channels,
                            std::span<const double> filter, std::size_t reversed,
                            double* __restrict__ out, std::size_t first) {
  double sum[B] = {};
  auto add_tap = [&](std::size_t f) {
    const double tap = filter[f];
    const double* __restrict__ row = newest - static_cast<std::ptrdiff_t>(f * channels) + first;
#pragma GCC unroll 8
    for (std::size_t b = 0; b < B; ++b) sum[b] += tap * row[b];
  };
  for (std::size_t f = reversed; f-- > 0;) add_tap(f);
  for (std::size_t f = reversed; f < filter.size(); ++f) add_tap(f);
  for (std::size_t b = 0; b < B; ++b) out[first + b] = sum[b];
}

// decimate_rows for one channel through decimate_8_outputs_paired: for callers built for AVX2
// (without it, GCC splits the 4-double vectors and the shuffles cost more than they save).
inline void decimate_one_channel_paired(const double* newest, std::size_t count,
                                        std::span<const double> filter, double* __restrict__ out) {
  std::size_t k = 0;
  if (filter.size() % 2 == 0) {
    for (; k + 8 <= count; k += 8) decimate_8_outputs_paired(newest + 2 * k, filter, out + k);
  }
  decimate_rows(newest + 2 * k, count - k, 1, filter, out + k);
}

// One channel: outputs [0, B) of decimate_rows_right_end, B at a time, each its own running sum
// in its own tap order, so that the additions of different outputs overlap.
template <std::size_t B>
void right_end_output_block(const double* newest, std::span<const double> filter,
                            const Decimation& dec, std::size_t first_output,
                            double* __restrict__ out) {
  const std::size_t taps = filter.size();
  std::size_t reversed[B];
  for (std::size_t b = 0; b < B; ++b) {
    reversed[b] = std::min(dec.reversed_taps(first_output + b), taps);
  }
  double sum[B] = {};
  for (std::size_t s = 0; s < taps; ++s) {
#pragma GCC unroll 8
    for (std::size_t b = 0; b < B; ++b) {
      const std::size_t f = s < reversed[b] ? reversed[b] - 1 - s : s;
      // Signed: the tap lies f - 2b samples before `newest + 2b`; an unsigned 2b - f would wrap,
      // and a pointer plus a wrapped offset is undefined (Clang's UBSan pointer-overflow).
      const auto offset = static_cast<std::ptrdiff_t>(2 * b) - static_cast<std::ptrdiff_t>(f);
      sum[b] += filter[f] * newest[offset];
    }
  }
  for (std::size_t b = 0; b < B; ++b) out[b] = sum[b];
}

// decimate_rows for outputs first_output .. first_output + count of a level whose decimation
// is `dec`, in PyWavelets' order: those whose taps run past the right end of the level's input
// sum their extension taps first, outwards (Decimation::reversed_taps).
inline void decimate_rows_right_end(const double* newest, std::size_t count, std::size_t channels,
                                    std::span<const double> filter, const Decimation& dec,
                                    std::size_t first_output, double* __restrict__ out) {
  if (channels == 1) {
    std::size_t k = 0;
    for (; k + 8 <= count; k += 8) {
      right_end_output_block<8>(newest + 2 * k, filter, dec, first_output + k, out + k);
    }
    if (k + 4 <= count) {
      right_end_output_block<4>(newest + 2 * k, filter, dec, first_output + k, out + k);
      k += 4;
    }
    if (k + 2 <= count) {
      right_end_output_block<2>(newest + 2 * k, filter, dec, first_output + k, out + k);
      k += 2;
    }
    if (k < count)
      right_end_output_block<1>(newest + 2 * k, filter, dec, first_output + k, out + k);
    return;
  }
  for (std::size_t k = 0; k < count; ++k) {
    const double* in = newest + 2 * k * channels;
    double* row_out = out + k * channels;
    const std::size_t reversed = std::min(dec.reversed_taps(first_output + k), filter.size());
    if (reversed == 0) {
      decimate_rows(in, 1, channels, filter, row_out);
      continue;
    }
    constexpr std::size_t kBlock = 8;
    std::size_t c = 0;
    for (; c + kBlock <= channels; c += kBlock) {
      decimate_reversed_head<kBlock>(in, channels, filter, reversed, row_out, c);
    }
    for (; c < channels; ++c) decimate_reversed_head<1>(in, channels, filter, reversed, row_out, c);
  }
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
