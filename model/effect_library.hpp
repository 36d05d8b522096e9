// The effect library of MODEL.md as fit candidates: for each effect (and each discrete variant,
// e.g. which chamber leaks to tank) the free parameters, their scaling for the solver, their
// physical bounds and a starting value. Effects are named verbatim as in MODEL.md.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "model/model_parameters.hpp"
#include "sim/parameters.hpp"

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
  // The smallest |main parameter| that is still an instance of the effect: a fifth of the low
  // end of MODEL.md's range (0: no such floor). A fit far below it is the model absorbing
  // something else, not the effect (docs/model-check.md: a clean capture's Coulomb friction
  // of 0.4 N, against MODEL.md's 50-400 N, acted only through tanh(v / 1e-3) as extra damping
  // at rest and soaked up the noise of each segment's starting velocity). A transducer lag
  // must also reach half the capture's sample period: a shorter one is a sub-sample delay of
  // the readings, not resolvable as a lag from the samples (see sample_period).
  double smallest() const;
  // Writes the discrete settings and parameter values into `e`.
  void apply(EffectParameters& e, const std::vector<double>& values) const;
  // The same into a model: an effect with an onset only into the effects from onset_s on, one
  // present from the start into both (ModelParameters::before).
  void apply(ModelParameters& p, const std::vector<double>& values) const;
  // Is a fitted main parameter a physical instance of the effect (e.g. a leak, not a source)?
  bool plausible(const std::vector<double>& values) const;
  // Set for a joint candidate (combine()): its parts, whose parameters `parameters` holds one
  // after the other; apply() and plausible() then act on each part's share of the values.
  std::vector<EffectCandidate> parts;
  // The capture's sample period [s] (0: unknown). A first-order lag tau_s shorter than half of
  // it passes 1 - exp(-dt / tau_s) > 86 % of a step within one sample: on the samples it is a
  // delay of tau_s < dt / 2, the same as a sub-sample timing mismatch between the model and
  // the capture (a friction reversal or a dead band's edge crossed between two samples), which
  // it then stands in for (docs/model-check.md: a 0.72 ms lag at 500 Hz named as a third cause
  // next to Coulomb friction and a valve bias).
  double sample_period = 0.0;
  // How large this effect's instances are on the rig judged, relative to the paper's rig
  // (RigScales): the smallest instance scales with it.
  double size = 1.0;
  // The rig's own spool time constant [s]: a spool_lag is a spool slower than it.
  double rig_spool_tau = sim::Parameters{}.tau;
  // > 0: the effect starts at this capture time [s] (FORMATS.md `onset_s`); 0: from the start.
  double onset_s = 0.0;
  // `values` cut into the parts' shares (one share, all of them, for a single candidate).
  std::vector<std::vector<double>> split(const std::vector<double>& values) const;
};

// Several effects fitted jointly (the model check's forward selection): every part's effect
// parameters free at once, each applied to the model in turn.
EffectCandidate combine(const std::vector<EffectCandidate>& parts);

// How an effect's size carries over from the paper's rig (MODEL.md's library ranges) to another
// rig: a leak as the same share of the valve's flow (C_L, C_E with Kv), a friction as the same
// share of the force the actuator can exert (A (ps - pt)), a droop as the same share of the
// supply lost at the valve's flow (R_s with (ps - pt) / (Kv sqrt(ps - pt))), a bias as the same
// share of the command's full scale. Transducer offsets, lags, air, dead band and ripple are
// properties of the part, not of the rig's size. 1 on the paper's rig.
struct RigScales {
  double leak = 1.0, force = 1.0, droop = 1.0, command = 1.0;
  static RigScales of(const sim::Parameters& rig);
};

// Every candidate, in MODEL.md's order. `ripple_hz` seeds the supply_ripple frequency (0: the
// capture shows no spectral line, and the ripple candidate is left out); oil_temperature
// ("Drifting operating conditions") is a candidate only when the capture has `temp`;
// `sample_period` is the capture's (EffectCandidate::sample_period).
// `rig`: the rig judged (its scales and spool time constant).
std::vector<EffectCandidate> effect_library(double ripple_hz, bool has_temperature = false,
                                            double sample_period = 0.0,
                                            const sim::Parameters& rig = sim::Parameters{});

// The eleven effect names of MODEL.md, in its order.
const std::vector<std::string>& effect_names();

}  // namespace leakmon::model
