// Test cases drawn afresh from MODEL.md: an effect of the library (or none) with parameters in
// its stated range, the calibratable parameters perturbed within theirs, a controller and a
// pseudorandom reference; the simulator (sim/) then makes the "measured" capture with sensor
// noise and spool flow noise on. Used by the tests and by `leakmon model evaluate`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/model_parameters.hpp"

#include "capture/capture.hpp"
#include "sim/scenario.hpp"

namespace leakmon::model {

struct TrueEffect {
  std::string effect;          // MODEL.md name
  std::string main_parameter;  // e.g. "C_L"
  double main_value = 0.0;     // its true value [SI]
};

struct SyntheticCase {
  std::uint64_t seed = 0;
  std::string effect = "none";      // MODEL.md name, several joined by '+', or "none"
  std::string main_parameter;       // the first effect's, e.g. "C_L"; empty for none
  double main_value = 0.0;          // the true value of that parameter [SI]
  std::vector<TrueEffect> effects;  // every effect present
  sim::Scenario scenario;
};

struct CaseSettings {
  double duration_s = 60.0;
  // > 0: each main parameter at its MODEL.md range's low end / edge or high end * edge (1: at
  // the edges, 1.5: beyond them) instead of drawn within the range.
  double edge = 0.0;
  bool record_temperature = true;  // oil_temperature cases: the capture has `temp`
};

// `effect` empty draws one of the eleven effects or "none" at random; otherwise that effect,
// "oil_temperature" (a warm-up during the capture) or several joined by '+'.
SyntheticCase draw_case(std::uint64_t seed, const std::string& effect = "",
                        const CaseSettings& settings = {});
capture::Capture simulate_case(const SyntheticCase& c);
// The generator's own model of the case (the "true model" whose held-out NRMSE is the best
// any extension can reach).
ModelParameters true_model(const SyntheticCase& c);

}  // namespace leakmon::model
