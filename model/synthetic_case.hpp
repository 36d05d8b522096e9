// Test cases drawn afresh from MODEL.md: an effect of the library (or none) with parameters in
// its stated range, the calibratable parameters perturbed within theirs, a controller and a
// pseudorandom reference; the simulator (sim/) then makes the "measured" capture with sensor
// noise and spool flow noise on. Used by the tests and by `leakmon model evaluate`.
#pragma once

#include <cstdint>
#include <string>

#include "capture/capture.hpp"
#include "sim/scenario.hpp"

namespace leakmon::model {

struct SyntheticCase {
  std::uint64_t seed = 0;
  std::string effect = "none";  // MODEL.md name or "none"
  std::string main_parameter;   // e.g. "C_L"; empty for none
  double main_value = 0.0;      // the true value of that parameter [SI]
  sim::Scenario scenario;
};

struct CaseSettings {
  double duration_s = 60.0;
};

// `effect` empty draws one of the eleven effects or "none" at random; otherwise that effect.
SyntheticCase draw_case(std::uint64_t seed, const std::string& effect = "",
                        const CaseSettings& settings = {});
capture::Capture simulate_case(const SyntheticCase& c);

}  // namespace leakmon::model
