// Single- and multi-level discrete wavelet transform with PyWavelets' semantics
// (pywt.dwt / pywt.wavedec): output lengths, convolution phase and extension modes.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "dsp/mode.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

// pywt.dwt_coeff_len: floor((n + F - 1) / 2), or ceil(n / 2) for periodization.
std::size_t dwt_coeff_len(std::size_t data_len, std::size_t filter_len, Mode mode);
// pywt.dwt_max_level: floor(log2(n / (F - 1))), 0 when n < F - 1.
int dwt_max_level(std::size_t data_len, std::size_t filter_len);

// How one decimating convolution reads its input: output k is
//   sum_f filter[f] * a_ext[2k + phase - f],  k in [0, n_out)
// where a_ext is the input extended by `left_ext` values before a[0] and `right_ext` after.
struct Decimation {
  std::size_t n_in = 0;
  std::size_t n_out = 0;
  std::size_t phase = 0;
  std::size_t left_ext = 0;
  std::size_t right_ext = 0;
  // PyWavelets' summation order: ascending taps, except that in the modes that fold the
  // signal back (symmetric, reflect, periodic, periodization, antisymmetric, antireflect) an
  // output whose taps run past the right end first adds its `reversed_taps(k)` taps that read
  // the extension, from the one next to the end outwards (tap reversed_taps(k) - 1 down to 0),
  // and then the others ascending. The order decides the last bits of a coefficient: on a large
  // level with little variation (8.65 MPa +- 100 Pa) ascending order alone moved the detail
  // coefficients there by up to ~1e-11 of the largest.
  bool reverse_right_overhang = false;

  std::size_t reversed_taps(std::size_t k) const {
    const std::size_t newest = 2 * k + phase;
    return reverse_right_overhang && newest >= n_in ? newest - n_in + 1 : 0;
  }
};
Decimation decimation(std::size_t n_in, std::size_t filter_len, Mode mode);

// Allocation-free core: `out` has dwt_coeff_len() values, `scratch` at least n + 2 * F.
void decimate(std::span<const double> signal, std::span<const double> filter, Mode mode,
              std::span<double> out, std::span<double> scratch);

struct DwtResult {
  std::vector<double> approx;
  std::vector<double> detail;
};
DwtResult dwt(std::span<const double> signal, const Wavelet& wavelet, Mode mode);

// pywt.wavedec order: [cA_level, cD_level, cD_level-1, ..., cD1]. Throws std::invalid_argument
// for level < 0 or an empty signal; like pywt, a level above dwt_max_level is computed anyway.
std::vector<std::vector<double>> wavedec(std::span<const double> signal, const Wavelet& wavelet,
                                         Mode mode, int level);

// The level-`level` detail coefficients of wavedec, computed into buffers sized once.
class DetailTransform {
 public:
  DetailTransform(std::size_t signal_len, const Wavelet& wavelet, Mode mode, int level);
  // signal.size() must equal signal_len. Allocation-free; the span stays valid until the next
  // call.
  std::span<const double> detail(std::span<const double> signal);
  std::size_t detail_len() const { return detail_.size(); }

 private:
  std::span<const double> lo_, hi_;
  Mode mode_;
  int level_;
  std::size_t signal_len_;
  std::vector<double> approx_a_, approx_b_, detail_, scratch_;
};

}  // namespace leakmon::dsp
