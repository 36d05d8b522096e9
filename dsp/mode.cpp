#include "dsp/mode.hpp"

#include <fmt/format.h>

#include <array>
#include <stdexcept>
#include <utility>

namespace leakmon::dsp {
namespace {

constexpr std::array<std::pair<Mode, std::string_view>, 9> kModeNames{{
    {Mode::zero, "zero"},
    {Mode::constant, "constant"},
    {Mode::symmetric, "symmetric"},
    {Mode::reflect, "reflect"},
    {Mode::periodic, "periodic"},
    {Mode::smooth, "smooth"},
    {Mode::periodization, "periodization"},
    {Mode::antisymmetric, "antisymmetric"},
    {Mode::antireflect, "antireflect"},
}};

}  // namespace

Mode parse_mode(std::string_view name) {
  for (const auto& [mode, mode_text] : kModeNames) {
    if (mode_text == name) return mode;
  }
  throw std::invalid_argument(fmt::format(
      "mode: unknown extension mode '{}' (valid: zero, constant, symmetric, reflect, periodic, "
      "smooth, periodization, antisymmetric, antireflect)",
      name));
}

std::string_view mode_name(Mode mode) {
  for (const auto& [m, mode_text] : kModeNames) {
    if (m == mode) return mode_text;
  }
  return "unknown";
}

}  // namespace leakmon::dsp
