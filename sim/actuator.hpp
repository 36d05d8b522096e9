// The right-hand side of MODEL.md's "Nominal model" with the effect library, written once: the
// simulator's Plant (with the spool flow noise w) and the model check's deterministic
// predictor (w = 0, model/actuator_model.hpp) both integrate these rates. Each term comes from
// its element's header: spool.hpp, valve.hpp (orifice, valve, null leak, overlap), supply.hpp
// (ripple, droop), leakage.hpp, chamber.hpp (volumes, pressures, entrained air), piston.hpp
// (piston, end stops), friction.hpp.
#pragma once

#include <algorithm>

#include "sim/chamber.hpp"
#include "sim/effects.hpp"
#include "sim/friction.hpp"
#include "sim/leakage.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"
#include "sim/piston.hpp"
#include "sim/spool.hpp"
#include "sim/supply.hpp"
#include "sim/valve.hpp"

namespace leakmon::sim {

// Parameters and effects flattened once, so the inner loop does no optional<> look-ups or
// repeated geometry. An effect that is off has the value that makes its term vanish.
struct ActuatorCoefficients {
  double A, V0, V_min, half_stroke;
  double pt, m, K_s, Kv, u_max, dp_lin, K_stop, c_stop;
  // The operating conditions (apply_conditions): viscosity ratio r = nu(40)/nu(T), supply
  // set-point ps0, and the coefficients that follow T: r C_n, b (0.5 + 0.5/r),
  // beta (1 - 0.003 (T - 40)). Nominal (r = 1, ps0 = ps) unless conditions are applied.
  double r, ps, C_n, b, beta;
  double tau_spool;                           // spool_lag's tau, else the nominal one
  double u_bias;                              // valve_bias u0
  double overlap;                             // valve_overlap d
  double ripple_dP, ripple_dQ, ripple_omega;  // supply_ripple (dQ: cos term, model check only)
  double droop_R_s;                           // supply_droop
  double C_E;                // external_leakage (as stated; the plant schedules it) ...
  int external_chamber;      //   ... from chamber 1 or 2
  double F_C;                // coulomb_friction
  double friction_velocity;  // its tanh scale: 1e-3 unless widened
  double alpha;              // entrained_air
  double lag_tau_s;          // sensor_lag ...
  bool lag_p1, lag_p2;       //   ... on which transducer
};

ActuatorCoefficients actuator_coefficients(const Parameters& params, const Effects& effects);

// MODEL.md "Drifting operating conditions": the oil at T [degC] and the supply set-point ps0
// [Pa]. At T = 40 and ps0 = params.ps every coefficient is exactly the nominal one (r(40) = 1).
void apply_conditions(ActuatorCoefficients& c, const Parameters& params, const Oil& oil,
                      double oil_temperature_C, double ps0) noexcept;

// Every flow and the supply pressure at one instant.
struct ActuatorFlows {
  double ps;              // supply pressure after ripple and droop [Pa]
  double opening;         // effective opening after noise and overlap
  double q1, q2;          // valve flows into chambers 1 and 2, null leakage included [m^3/s]
  double q_supply;        // flow out of the supply port [m^3/s]
  double q_int;           // cross-port leakage 1 -> 2 [m^3/s]
  double q_ext1, q_ext2;  // external leakage to tank [m^3/s]
  double C_L;             // internal leakage coefficient at the oil's temperature (r C_L)
};

// Leak sizes are stated at 40 degC; the internal leak's flow follows the viscosity ratio.
inline double internal_leak_coefficient(const ActuatorCoefficients& c, double C_L40) noexcept {
  return c.r * C_L40;
}

// p1, p2 already clamped at 0 (no cavitation); w is the spool flow noise; C_L and C_E the
// internal and external leakage coefficients in force at t (leak sizes are stated at 40 degC:
// the internal leak follows the viscosity ratio r, the external one keeps its C_E, MODEL.md).
[[gnu::always_inline]] inline ActuatorFlows actuator_flows(const ActuatorCoefficients& c, double t,
                                                           double xs, double w, double C_L,
                                                           double C_E, double p1,
                                                           double p2) noexcept {
  ActuatorFlows f{};
  f.opening = xs + w;
  if (c.overlap > 0.0) f.opening = overlapped_opening(f.opening, c.overlap);
  f.ps = rippled_supply(c.ps, c.ripple_dP, c.ripple_dQ, c.ripple_omega, t);
  if (c.droop_R_s > 0.0) {
    f.ps = drooped_supply(f.ps, c.droop_R_s, {f.opening, p1, p2, c.pt, c.Kv, c.dp_lin, c.C_n});
  }
  const ValveFlows valve = valve_flows(f.opening, f.ps, c.pt, p1, p2, c.Kv, c.dp_lin, c.C_n);
  f.q1 = valve.q1;
  f.q2 = valve.q2;
  f.q_supply = valve.q_supply;
  f.C_L = internal_leak_coefficient(c, C_L);
  f.q_int = cross_port_flow(f.C_L, p1, p2);
  if (C_E != 0.0) {  // the model check's fit may try a negative C_E
    if (c.external_chamber == 1) {
      f.q_ext1 = external_leak_flow(C_E, p1, c.pt);
    } else {
      f.q_ext2 = external_leak_flow(C_E, p2, c.pt);
    }
  }
  return f;
}

struct ActuatorRates {
  double xs, x, v, p1, p2;  // time derivatives of the states
  double inflow1, inflow2;  // net port flow into each chamber [m^3/s]
  double q_int;             // cross-port leakage [m^3/s]
  double p1_clamped, p2_clamped;
};

// spool_in = spool_command(u + u0, u_max), constant while u is held. p1_state, p2_state are the
// integrated pressures (an RK stage may dip below 0; the equations see them clamped).
[[gnu::always_inline]] inline ActuatorRates actuator_rates(const ActuatorCoefficients& c, double t,
                                                           double spool_in, double w, double C_L,
                                                           double C_E, double xs, double x,
                                                           double v, double p1_state,
                                                           double p2_state) noexcept {
  const double p1 = std::max(p1_state, 0.0);
  const double p2 = std::max(p2_state, 0.0);
  const ActuatorFlows f = actuator_flows(c, t, xs, w, C_L, C_E, p1, p2);
  ActuatorRates r;
  r.p1_clamped = p1;
  r.p2_clamped = p2;
  r.q_int = f.q_int;
  r.xs = (spool_in - xs) / c.tau_spool;

  const double V1 = std::max(c.V0 + c.A * x, c.V_min);
  const double V2 = std::max(c.V0 - c.A * x, c.V_min);
  r.inflow1 = f.q1 - f.q_int - f.q_ext1;
  r.inflow2 = f.q2 + f.q_int - f.q_ext2;
  r.p1 = chamber_pressure_rate(bulk_modulus(c.beta, c.alpha, p1), V1, r.inflow1, c.A * v);
  r.p2 = chamber_pressure_rate(bulk_modulus(c.beta, c.alpha, p2), V2, r.inflow2, -c.A * v);
  if (p1_state <= 0.0 && r.p1 < 0.0) r.p1 = 0.0;
  if (p2_state <= 0.0 && r.p2 < 0.0) r.p2 = 0.0;

  const double friction = c.F_C != 0.0 ? coulomb_friction(c.F_C, v, c.friction_velocity) : 0.0;
  const double stop = end_stop_force(x, v, c.half_stroke, c.K_stop, c.c_stop);
  r.x = v;
  r.v = piston_acceleration(c.A, p1, p2, c.m, c.b, c.K_s, x, v, friction, stop);
  return r;
}

// sensor_lag: tau_s dp_m/dt = p - p_m.
inline double transducer_lag_rate(double p, double p_reading, double tau_s) noexcept {
  return (p - p_reading) / tau_s;
}

}  // namespace leakmon::sim
