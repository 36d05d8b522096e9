#include "sim/actuator.hpp"

#include <numbers>

namespace leakmon::sim {

ActuatorCoefficients actuator_coefficients(const Parameters& params, const Effects& effects) {
  ActuatorCoefficients c{};
  c.A = params.A();
  c.V0 = params.V0();
  // A floor on the volumes keeps the equations finite if the piston is driven into a stop.
  c.V_min = 1e-3 * (params.V_dead + params.V_line);
  c.half_stroke = 0.5 * params.L;
  c.pt = params.pt;
  c.m = params.m;
  c.K_s = params.K_s;
  c.Kv = params.Kv;
  c.u_max = params.u_max;
  c.dp_lin = params.dp_lin;
  c.K_stop = params.K_stop;
  c.c_stop = params.c_stop;
  c.tau_spool = effects.spool_lag ? effects.spool_lag->tau : params.tau;
  c.u_bias = effects.valve_bias ? effects.valve_bias->u0 : 0.0;
  c.overlap = effects.valve_overlap ? effects.valve_overlap->d : 0.0;
  if (effects.supply_ripple) {
    c.ripple_dP = effects.supply_ripple->dP;
    c.ripple_omega = 2.0 * std::numbers::pi * effects.supply_ripple->f;
  }
  c.droop_R_s = effects.supply_droop ? effects.supply_droop->R_s : 0.0;
  c.external_chamber = 1;
  if (effects.external_leakage) {
    c.C_E = effects.external_leakage->C_E;
    c.external_chamber = effects.external_leakage->chamber;
  }
  c.F_C = effects.coulomb_friction ? effects.coulomb_friction->F_C : 0.0;
  c.friction_velocity = kCoulombVelocityScale;
  c.alpha = effects.entrained_air ? effects.entrained_air->alpha : 0.0;
  c.lag_tau_s = 1.0;
  if (effects.sensor_lag) {
    c.lag_tau_s = effects.sensor_lag->tau_s;
    c.lag_p1 = effects.sensor_lag->channel == PressureChannel::p1;
    c.lag_p2 = effects.sensor_lag->channel == PressureChannel::p2;
  }
  apply_conditions(c, params, Oil::standard(), kReferenceTemperature, params.ps);
  return c;
}

void apply_conditions(ActuatorCoefficients& c, const Parameters& params, const Oil& oil,
                      double oil_temperature_C, double ps0) noexcept {
  c.r = oil.ratio(oil_temperature_C);
  c.ps = ps0;
  c.C_n = c.r * params.C_n;
  c.b = params.b * friction_factor(c.r);
  c.beta = params.beta * bulk_modulus_factor(oil_temperature_C);
}

}  // namespace leakmon::sim
