// The model check's predictor: the simulator's actuator (the rates of sim/actuator.hpp, every
// equation of MODEL.md written once) in a deterministic mode, driven open loop by the measured
// u. The spool flow noise w of the nominal model is process noise with zero mean, so the
// predictor uses its expectation, w = 0. What it adds to the simulator's Plant is what fitting
// needs: the calibratable parameters and every effect parameter settable per evaluation, a
// single lagging-transducer state, an adaptive sub-step count and, where even that cannot
// resolve Coulomb friction's tanh(v / 1e-3), sticking with the velocity slaved to the force.
#pragma once

#include "model/model_parameters.hpp"
#include "sim/actuator.hpp"
#include "sim/parameters.hpp"

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
  // rig: the rig table; its beta, Kv, m, b are replaced by parameters.calibration.
  explicit ActuatorModel(const ModelParameters& parameters,
                         const sim::Parameters& rig = sim::Parameters::nominal());

  const ModelParameters& parameters() const { return parameters_; }
  // The rig table with the calibration applied.
  const sim::Parameters& rig() const { return rig_; }
  const sim::ActuatorCoefficients& coefficients() const { return c_; }
  double spool_tau() const { return c_.tau_spool; }
  // Integration sub-steps per sample interval: enough for RK4 to stay stable, since Coulomb
  // friction's tanh(v / 1e-3) is a very stiff damper near v = 0.
  int substeps(double dt) const;
  // The tanh velocity scale sub-step h resolves: 1e-3, or wider where h cannot (then a
  // positive F_C sticks instead, advance(); a fit's negative trial F_C takes the wider band).
  double friction_velocity(double h) const;

  // Advances `state` from t0 over dt with the valve command u held (zero-order hold). w is the
  // spool flow noise held over the step: 0 (its mean) for prediction; the noise floor
  // (SegmentPredictor::noise_floor) draws it.
  void advance(ActuatorState& state, double u, double t0, double dt, double w = 0.0) const;
  Reading read(const ActuatorState& state) const;

  // The same step with the coefficients of the oil at T [degC] (oil_temperature): the oil's
  // viscosity slope is the model's visc_slope (ISO VG 46's viscosity at 40 degC, the one at
  // 100 degC chosen to give that slope), the laws of apply_conditions (sim/actuator.hpp).
  sim::ActuatorCoefficients coefficients_at(double T) const;
  void advance(ActuatorState& state, double u, double t0, double dt, double w,
               const sim::ActuatorCoefficients& c) const;

  // Spool input sat((u + u0) / u_max) of MODEL.md's spool equation.
  double spool_input(double u) const;

 private:
  // The largest eigenvalue magnitude substeps() resolves: fixed by the coefficients, so it is
  // worked out once rather than on every sample interval of every segment.
  double fastest_rate(bool with_friction) const;
  static int substeps_at_rate(double rate, double dt);
  ActuatorState derivative(const sim::ActuatorCoefficients& c, const ActuatorState& s,
                           double spool_in, double w, double t) const;
  template <bool kStuck>
  ActuatorState rate(const sim::ActuatorCoefficients& c, const ActuatorState& s, double spool_in,
                     double w, double t) const;
  template <bool kStuck>
  void rk4_step(ActuatorState& state, const sim::ActuatorCoefficients& c, double spool_in, double t,
                double h, double w) const;
  void advance_sticking(ActuatorState& state, double spool_in, double t0, double h, int n, double w,
                        const sim::ActuatorCoefficients& c) const;
  [[gnu::always_inline]] static double stick_ratio(const sim::ActuatorCoefficients& c,
                                                   const ActuatorState& s);
  [[gnu::always_inline]] static double sticking_velocity(const sim::ActuatorCoefficients& c,
                                                         double ratio);
  // Beyond this share of F_C the force breaks the piston free (tanh^-1 of it: 3.8 bands).
  static constexpr double kMaxStickRatio = 0.999;

  ModelParameters parameters_;
  sim::Parameters rig_;
  sim::ActuatorCoefficients c_;
  bool lagging_ = false;
  double fastest_rate_ = 0.0;
  double fastest_rate_without_friction_ = 0.0;
  sim::Oil oil_ = sim::Oil::standard();
};

}  // namespace leakmon::model
