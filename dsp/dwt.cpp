#include "dsp/dwt.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "dsp/extension.hpp"

namespace leakmon::dsp {

std::size_t dwt_coeff_len(std::size_t data_len, std::size_t filter_len, Mode mode) {
  if (mode == Mode::periodization) return (data_len + 1) / 2;
  return (data_len + filter_len - 1) / 2;
}

int dwt_max_level(std::size_t data_len, std::size_t filter_len) {
  if (filter_len < 2 || data_len < filter_len - 1) return 0;
  // Integer form of floor(log2(n / (F - 1))): the largest L with (F - 1) * 2^L <= n.
  int level = 0;
  while ((filter_len - 1) << (level + 1) <= data_len) ++level;
  return level;
}

Decimation decimation(std::size_t n_in, std::size_t filter_len, Mode mode) {
  Decimation d;
  d.n_in = n_in;
  d.n_out = dwt_coeff_len(n_in, filter_len, mode);
  // pywt starts the periodization convolution half a filter in, the others at index 1.
  d.phase = mode == Mode::periodization ? filter_len / 2 : 1;
  d.left_ext = filter_len - 1 > d.phase ? filter_len - 1 - d.phase : 0;
  const std::size_t last_read = d.n_out == 0 ? 0 : 2 * (d.n_out - 1) + d.phase;
  d.right_ext = last_read + 1 > n_in ? last_read + 1 - n_in : 0;
  d.reverse_right_overhang = mode != Mode::zero && mode != Mode::constant && mode != Mode::smooth;
  return d;
}

void decimate(std::span<const double> signal, std::span<const double> filter, Mode mode,
              std::span<double> out, std::span<double> scratch) {
  const Decimation d = decimation(signal.size(), filter.size(), mode);
  const std::size_t n = signal.size();
  auto at = [&](std::size_t i) { return signal[i]; };
  // scratch holds the extended signal: a_ext[i] at scratch[left_ext + i].
  double* ext = scratch.data() + d.left_ext;
  for (std::size_t m = 1; m <= d.left_ext; ++m)
    ext[-static_cast<std::ptrdiff_t>(m)] = extend_before_start(mode, n, m, at);
  std::copy(signal.begin(), signal.end(), ext);
  for (std::size_t m = 1; m <= d.right_ext; ++m) ext[n - 1 + m] = extend_after_end(mode, n, m, at);
  const std::size_t taps = filter.size();
  for (std::size_t k = 0; k < d.n_out; ++k) {
    const double* newest = scratch.data() + d.left_ext + 2 * k + d.phase;
    const std::size_t reversed = std::min(d.reversed_taps(k), taps);
    double sum = 0.0;
    for (std::size_t f = reversed; f-- > 0;)
      sum += filter[f] * newest[-static_cast<std::ptrdiff_t>(f)];
    for (std::size_t f = reversed; f < taps; ++f)
      sum += filter[f] * newest[-static_cast<std::ptrdiff_t>(f)];
    out[k] = sum;
  }
}

DwtResult dwt(std::span<const double> signal, const Wavelet& wavelet, Mode mode) {
  if (signal.empty()) throw std::invalid_argument("dwt: empty signal");
  const std::size_t n_out = dwt_coeff_len(signal.size(), wavelet.filter_length(), mode);
  DwtResult result{std::vector<double>(n_out), std::vector<double>(n_out)};
  std::vector<double> scratch(signal.size() + 2 * wavelet.filter_length());
  decimate(signal, wavelet.dec_lo, mode, result.approx, scratch);
  decimate(signal, wavelet.dec_hi, mode, result.detail, scratch);
  return result;
}

std::vector<std::vector<double>> wavedec(std::span<const double> signal, const Wavelet& wavelet,
                                         Mode mode, int level) {
  if (level < 0) throw std::invalid_argument(fmt::format("wavedec: level {} is negative", level));
  if (signal.empty()) throw std::invalid_argument("wavedec: empty signal");
  std::vector<std::vector<double>> details;
  std::vector<double> approx(signal.begin(), signal.end());
  for (int l = 0; l < level; ++l) {
    DwtResult step = dwt(approx, wavelet, mode);
    details.push_back(std::move(step.detail));
    approx = std::move(step.approx);
  }
  std::vector<std::vector<double>> coeffs{std::move(approx)};
  coeffs.insert(coeffs.end(), std::make_move_iterator(details.rbegin()),
                std::make_move_iterator(details.rend()));
  return coeffs;
}

DetailTransform::DetailTransform(std::size_t signal_len, const Wavelet& wavelet, Mode mode,
                                 int level)
    : lo_(wavelet.dec_lo),
      hi_(wavelet.dec_hi),
      mode_(mode),
      level_(level),
      signal_len_(signal_len) {
  if (level < 1) throw std::invalid_argument(fmt::format("level: {} is below 1", level));
  // Short signals grow at first (n -> (n + F - 1) / 2), so size by the longest level.
  const std::size_t taps = wavelet.filter_length();
  std::size_t n = signal_len;
  std::size_t longest = n;
  for (int l = 1; l < level; ++l) {
    n = dwt_coeff_len(n, taps, mode);
    longest = std::max(longest, n);
  }
  approx_a_.resize(longest);
  approx_b_.resize(longest);
  detail_.resize(dwt_coeff_len(n, taps, mode));
  scratch_.resize(longest + 2 * taps);
}

std::span<const double> DetailTransform::detail(std::span<const double> signal) {
  std::span<const double> input = signal.first(signal_len_);
  std::span<double> spare = approx_a_;
  std::span<double> other = approx_b_;
  for (int l = 1; l < level_; ++l) {
    const std::size_t n_out = dwt_coeff_len(input.size(), lo_.size(), mode_);
    decimate(input, lo_, mode_, spare.first(n_out), scratch_);
    input = spare.first(n_out);
    std::swap(spare, other);
  }
  decimate(input, hi_, mode_, detail_, scratch_);
  return detail_;
}

}  // namespace leakmon::dsp
