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
#include "sim/rig_description.hpp"
#include "sim/scenario.hpp"

namespace leakmon::model {

struct TrueEffect {
  std::string effect;          // MODEL.md name
  std::string main_parameter;  // e.g. "C_L"
  double main_value = 0.0;     // its true value [SI]
};

struct SyntheticCase {
  std::uint64_t seed = 0;
  // The description the model check is told: the paper's rig, another rig's true
  // description, or that description with one value mis-stated (`misstated`).
  sim::RigDescription told;
  std::string misstated;            // the rig key stated wrong; empty when told the truth
  double misstated_true = 0.0;      // its true value [SI] ...
  double misstated_stated = 0.0;    // ... and the one told
  double onset_s = 0.0;             // > 0: the effects appear at this capture time
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
  // Another rig (sim::draw_other_rig) instead of the paper's: the effects sized for it
  // (RigScales), its calibratable values perturbed within MODEL.md's ranges around the
  // description told.
  bool other_rig = false;
  // A rig key to state wrong (supply_pressure 15-30 % off, load_stiffness 40-80 % off, either
  // direction; a rig without a spring is drawn again for the latter).
  std::string misstate = "";
  // The effects appear inside the capture, at 20-80 % of its length (Scenario::change).
  bool onset = false;
  // A random test program of MODEL.md's phases instead of the paper's steps (capture_program()).
  bool program = false;
};

// The keys a `misstated` case may state wrong, and how far off (relative, either direction).
struct Misstatement {
  std::string key;
  double low, high;
};
const std::vector<Misstatement>& misstatements();

// `effect` empty draws one of the eleven effects or "none" at random; otherwise that effect,
// "oil_temperature" (a warm-up during the capture) or several joined by '+'.
SyntheticCase draw_case(std::uint64_t seed, const std::string& effect = "",
                        const CaseSettings& settings = {});
capture::Capture simulate_case(const SyntheticCase& c);
// The generator's own model of the case (the "true model" whose held-out NRMSE is the best
// any extension can reach).
ModelParameters true_model(const SyntheticCase& c);

}  // namespace leakmon::model
