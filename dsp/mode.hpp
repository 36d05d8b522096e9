// Signal extension modes of PyWavelets, under PyWavelets' names.
#pragma once

#include <string_view>

namespace leakmon::dsp {

enum class Mode {
  zero,
  constant,
  symmetric,
  reflect,
  periodic,
  smooth,
  periodization,
  antisymmetric,
  antireflect
};

// Throws std::invalid_argument listing the valid names.
Mode parse_mode(std::string_view name);
std::string_view mode_name(Mode mode);

}  // namespace leakmon::dsp
