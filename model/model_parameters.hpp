// Everything that distinguishes one actuator model from another: the calibratable parameters
// (MODEL.md "Calibratable parameters") and the effect library's parameters (MODEL.md "Effect
// library", names verbatim). Every effect defaults to "absent", so a default-constructed
// EffectParameters is the nominal model.
#pragma once

#include "sim/parameters.hpp"

namespace leakmon::model {

// Starts at the rig table's nominal values (sim/parameters.hpp, the one table).
struct Calibration {
  double beta = sim::Parameters{}.beta;  // effective bulk modulus [Pa]
  double Kv = sim::Parameters{}.Kv;      // valve coefficient [m^3/(s sqrt(Pa))]
  double m = sim::Parameters{}.m;        // moving mass [kg]
  double b = sim::Parameters{}.b;        // viscous friction [N s/m]

  // The calibratable values a rig table states (MODEL.md "Other rigs": calibrated within
  // "Calibratable parameters"' ranges around them).
  static Calibration of(const sim::Parameters& rig) { return {rig.beta, rig.Kv, rig.m, rig.b}; }
};

enum class PressureChannel { p1, p2 };

struct EffectParameters {
  double C_L = 0.0;          // internal_leakage [m^3/(s Pa)]
  double C_E = 0.0;          // external_leakage [m^3/(s Pa)]
  int external_chamber = 1;  //   ... its chamber, 1 or 2
  double F_C = 0.0;          // coulomb_friction [N]
  double alpha = 0.0;        // entrained_air, free-air fraction
  double d = 0.0;            // valve_overlap, fraction of spool travel
  double u0 = 0.0;           // valve_bias [V]
  double spool_tau = 0.0;    // spool_lag: true tau [s]; 0 = nominal
  double ripple_dP = 0.0;    // supply_ripple amplitude [Pa] (sin term)
  double ripple_dQ = 0.0;    //   ... cos term: phase freedom while fitting
  double ripple_f = 0.0;     //   ... frequency [Hz]
  double R_s = 0.0;          // supply_droop [Pa s/m^3]
  double offset = 0.0;       // sensor_offset [Pa]
  PressureChannel offset_channel = PressureChannel::p1;
  double tau_s = 0.0;  // sensor_lag [s]
  PressureChannel lag_channel = PressureChannel::p1;
  // oil_temperature: -d ln(nu)/dT at 40 degC [1/K]; 0 = the model ignores the oil's
  // temperature (needs the capture's `temp` column).
  double visc_slope = 0.0;
};

struct ModelParameters {
  Calibration calibration;
  EffectParameters effects;
  // An effect that starts inside the capture (FORMATS.md `onset_s`): before onset_s the model
  // runs with `before` (the effects present from the start), from onset_s on with `effects`.
  // 0: every effect is present from the start and `before` is unused.
  double onset_s = 0.0;
  EffectParameters before;
};

}  // namespace leakmon::model
