// Orthogonal wavelet filter banks under PyWavelets' names: haar, db1..db20, sym2..sym20,
// coif1..coif5. The coefficients are PyWavelets' own (generated into wavelet_tables.cpp).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::dsp {

struct Wavelet {
  std::string_view name;
  std::span<const double> dec_lo;  // decomposition low-pass, as pywt.Wavelet(name).dec_lo
  std::span<const double> dec_hi;
  std::span<const double> rec_lo;
  std::span<const double> rec_hi;

  std::size_t filter_length() const { return dec_lo.size(); }
};

// Throws std::invalid_argument naming the unknown wavelet and the families offered.
const Wavelet& wavelet(std::string_view name);
bool has_wavelet(std::string_view name);
std::vector<std::string_view> wavelet_names();

}  // namespace leakmon::dsp
