// The actuator of MODEL.md as a deterministic ODE, extended by any effect of the library.
// The model check predicts the measured signals with it; the spool flow noise w of the nominal
// model is process noise with zero mean, so the predictor uses its expectation, w = 0.
#pragma once

#include "model/model_parameters.hpp"
#include "model/rig_constants.hpp"

namespace leakmon::model {

struct ActuatorState {
  double xs = 0.0;  // spool position, normalised
  double x = 0.0;   // piston position [m]
  double v = 0.0;   // piston velocity [m/s]
  double p1 = 0.0;  // true chamber pressures [Pa]
  double p2 = 0.0;
  double s = 0.0;  // reading of the lagging transducer (sensor_lag) [Pa]
};

// What the instruments report for a state: position and the two pressure readings.
struct Reading {
  double x = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
};

class ActuatorModel {
 public:
  ActuatorModel(const ModelParameters& parameters, const RigConstants& rig = {});

  const ModelParameters& parameters() const { return parameters_; }
  const RigConstants& rig() const { return rig_; }
  double spool_tau() const { return spool_tau_; }
  // Integration sub-steps per sample interval: enough for RK4 to stay stable, since Coulomb
  // friction's tanh(v / 1e-3) is a very stiff damper near v = 0.
  int substeps(double dt) const;

  // Advances `state` from t0 over dt with the valve command u held (zero-order hold).
  void advance(ActuatorState& state, double u, double t0, double dt) const;
  Reading read(const ActuatorState& state) const;

  // Spool input sat((u + u0) / u_max) of MODEL.md's spool equation.
  double spool_input(double u) const;
  // Supply pressure after ripple and droop; solves droop's algebraic loop.
  double supply_pressure(double t, double opening, double p1, double p2) const;
  double bulk_modulus(double p) const;

 private:
  ActuatorState derivative(const ActuatorState& s, double spool_in, double t, double v_fric) const;
  double friction_velocity(double h) const;
  double opening(double xs) const;

  ModelParameters parameters_;
  RigConstants rig_;
  double spool_tau_;
  double half_volume_;
};

}  // namespace leakmon::model
