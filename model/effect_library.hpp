// The effect library of MODEL.md as fit candidates: for each effect (and each discrete variant,
// e.g. which chamber leaks to tank) the free parameters, their scaling for the solver, their
// physical bounds and a starting value. Effects are named verbatim as in MODEL.md.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "model/model_parameters.hpp"

namespace leakmon::model {

struct FreeParameter {
  std::string name;  // MODEL.md's name; empty for a solver-only parameter (ripple phase)
  double scale;      // the solver works on value / scale, near 1
  double initial;    // starting value [SI]
  double lower;      // values stay in [lower, upper] (the fit mirrors them back, apply clamps)
  double upper;
};

struct EffectCandidate {
  std::string effect;                     // MODEL.md's name
  std::string variant;                    // "chamber 2", "p1", ... ; empty when the effect has none
  std::vector<FreeParameter> parameters;  // the first one is the effect's main parameter
  // Writes the discrete settings and parameter values into `e`.
  void apply(EffectParameters& e, const std::vector<double>& values) const;
  // Is a fitted main parameter a physical instance of the effect (e.g. a leak, not a source)?
  bool plausible(const std::vector<double>& values) const;
};

// Every candidate, in MODEL.md's order. `ripple_hz` seeds the supply_ripple frequency (0: the
// capture shows no spectral line, and the ripple candidate is left out).
std::vector<EffectCandidate> effect_library(double ripple_hz);

// The eleven effect names of MODEL.md, in its order.
const std::vector<std::string>& effect_names();

}  // namespace leakmon::model
