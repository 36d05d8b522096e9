// The generated filter-bank tables (dsp/wavelet_tables.cpp, from dsp/tools/gen_wavelets.py).
#pragma once

#include <span>
#include <string_view>

namespace leakmon::dsp::tables {

struct FilterBank {
  std::string_view name;
  std::span<const double> dec_lo, dec_hi, rec_lo, rec_hi;
};

std::span<const FilterBank> filter_banks();

}  // namespace leakmon::dsp::tables
