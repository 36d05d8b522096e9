// What a sliding-window detail feature is, apart from how it is computed: its parameters
// (wavelet, level, window, step, extension mode) and its value for one window. Shared by the
// streaming and the block engines and by the incremental plan both use, which therefore include
// this, not each other.
#pragma once

#include <cstddef>
#include <limits>
#include <string>

#include "dsp/mode.hpp"

namespace leakmon::dsp {

struct FeatureParams {
  std::string wavelet = "db8";
  int level = 2;
  std::size_t window = 400;
  std::size_t step = 20;
  Mode mode = Mode::symmetric;
};

// Throws std::invalid_argument naming the offending parameter and the reason.
void validate(const FeatureParams& params);

struct DetailFeature {
  double rms = std::numeric_limits<double>::quiet_NaN();
  double energy = std::numeric_limits<double>::quiet_NaN();
  bool valid = false;  // false: the window contained a gap (NaN sample)
};

}  // namespace leakmon::dsp
