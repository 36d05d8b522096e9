#include "sim/plant.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim/chamber.hpp"
#include "sim/friction.hpp"
#include "sim/piston.hpp"
#include "sim/spool.hpp"
#include "sim/supply.hpp"
#include "sim/valve.hpp"

namespace leakmon::sim {
namespace {

enum Index { kXs, kX, kV, kP1, kP2, kP1Transducer, kP2Transducer, kMassIn1, kMassIn2, kLeaked };

// RK4's stability limit on the negative real axis is h |lambda| = 2.78; staying at 2 keeps
// the numerical damping of fast modes small.
constexpr double kStabilityLimit = 2.0;
// The accuracy-chosen default: 8 steps per 2 ms sample (250 us, the flow-noise grid). Halving
// it changes nominal trajectories by tens of pascals, two orders below the 5 kPa pressure LSB
// (tests/sim/numerics_test.cpp checks this on every preset).
constexpr int kDefaultStepsPerSample = 8;

}  // namespace

double automatic_integration_step(const Parameters& params, const Effects& effects,
                                  double sample_rate_hz) {
  const double period = 1.0 / sample_rate_hz;
  double h = period / kDefaultStepsPerSample;
  // Fastest real eigenvalues of the plant: the dampers over the mass, Coulomb friction's tanh
  // slope over the mass, the spool, a lagging transducer, and a chamber at its smallest
  // volume (piston at a stop) fed through a fully open laminar orifice; the end-stop spring's
  // frequency.
  double fastest = (params.b + params.c_stop) / params.m;
  if (effects.coulomb_friction) {
    fastest += effects.coulomb_friction->F_C / (kCoulombVelocityScale * params.m);
  }
  const double tau = effects.spool_lag ? effects.spool_lag->tau : params.tau;
  const double hydraulic = params.beta * (params.Kv / std::sqrt(params.dp_lin) + 2.0 * params.C_n) /
                           (params.V_dead + params.V_line);
  fastest = std::max({fastest, 1.0 / tau, hydraulic, std::sqrt(params.K_stop / params.m)});
  if (effects.sensor_lag) fastest = std::max(fastest, 1.0 / effects.sensor_lag->tau_s);
  h = std::min(h, kStabilityLimit / fastest);
  return period / std::ceil(period / h - 1e-9);
}

Plant::Plant(const Parameters& params, const Effects& effects, std::uint64_t noise_seed,
             double integration_step_s)
    : params_(params),
      effects_(effects),
      noise_(params.sigma_w, params.tau_w, kNoiseGridStep, noise_seed),
      step_(integration_step_s > 0.0 ? integration_step_s
                                     : automatic_integration_step(params, effects, 500.0)) {
  c_ = {};
  c_.A = params.A();
  c_.V0 = params.V0();
  // A floor on the volumes keeps the equations finite if the piston is driven into a stop.
  c_.V_min = 1e-3 * (params.V_dead + params.V_line);
  c_.half_stroke = 0.5 * params.L;
  c_.tau_spool = effects.spool_lag ? effects.spool_lag->tau : params.tau;
  c_.u_bias = effects.valve_bias ? effects.valve_bias->u0 : 0.0;
  c_.overlap = effects.valve_overlap ? effects.valve_overlap->d : 0.0;
  if (effects.supply_ripple) {
    c_.ripple_dP = effects.supply_ripple->dP;
    c_.ripple_omega = 2.0 * std::numbers::pi * effects.supply_ripple->f;
  }
  c_.droop_R_s = effects.supply_droop ? effects.supply_droop->R_s : 0.0;
  if (effects.external_leakage) {
    external_leak_ = {effects.external_leakage->C_E, effects.external_leakage->onset_s,
                      effects.external_leakage->ramp_s};
    c_.external_chamber = effects.external_leakage->chamber;
  }
  c_.F_C = effects.coulomb_friction ? effects.coulomb_friction->F_C : 0.0;
  c_.alpha = effects.entrained_air ? effects.entrained_air->alpha : 0.0;
  if (effects.sensor_lag) {
    c_.lag_tau_s = effects.sensor_lag->tau_s;
    c_.lag_p1 = effects.sensor_lag->channel == PressureChannel::p1;
    c_.lag_p2 = effects.sensor_lag->channel == PressureChannel::p2;
  }
  if (effects.internal_leakage) {
    leak_ = {effects.internal_leakage->C_L, effects.internal_leakage->onset_s,
             effects.internal_leakage->ramp_s};
  }
  set_conditions(kReferenceTemperature, params.ps);
  reset();
}

void Plant::set_conditions(double oil_temperature_C, double ps0) noexcept {
  temperature_ = oil_temperature_C;
  // r(40) is exactly 1 (Oil::ratio), and so are both factors: a rig at 40 degC keeps the
  // nominal coefficients bit for bit.
  c_.r = oil_.ratio(oil_temperature_C);
  c_.C_n = c_.r * params_.C_n;
  c_.b = params_.b * friction_factor(c_.r);
  c_.beta = params_.beta * bulk_modulus_factor(oil_temperature_C);
  c_.ps0 = ps0;
}

void Plant::set_oil(const Oil& oil) {
  oil_ = oil;
  set_conditions(temperature_, c_.ps0);
}

void Plant::reset() {
  noise_.reset();
  PlantState rest;
  rest.p1 = rest.p2 = 0.5 * (params_.ps + params_.pt);
  set_state(rest);
  time_ = 0.0;
}

void Plant::set_state(const PlantState& state) {
  y_ << state.xs, state.x, state.v, state.p1, state.p2, state.p1, state.p2, state.mass_in1,
      state.mass_in2, state.leaked_volume;
  store(y_);
}

void Plant::store(const Vector& y) {
  state_ = {y[kXs],           y[kX],       y[kV],       y[kP1],    y[kP2], y[kP1Transducer],
            y[kP2Transducer], y[kMassIn1], y[kMassIn2], y[kLeaked]};
}

void Plant::set_integration_step(double h) { step_ = h; }

void Plant::set_internal_leak(double C_L, double onset_s, double ramp_s) noexcept {
  leak_ = {C_L, onset_s, ramp_s};
}

PlantFlows Plant::evaluate(double t, double step_midpoint, double xs, double p1, double p2,
                           double w) const noexcept {
  const Parameters& p = params_;
  PlantFlows f{};
  f.w = w;
  f.opening = xs + w;
  if (c_.overlap > 0.0) f.opening = overlapped_opening(f.opening, c_.overlap);

  f.ps = c_.ps0;
  if (c_.ripple_dP != 0.0) f.ps += c_.ripple_dP * std::sin(c_.ripple_omega * t);
  if (c_.droop_R_s > 0.0) {
    f.ps = drooped_supply(f.ps, c_.droop_R_s, {f.opening, p1, p2, p.pt, p.Kv, p.dp_lin, c_.C_n});
  }

  const ValveFlows valve = valve_flows(f.opening, f.ps, p.pt, p1, p2, p.Kv, p.dp_lin, c_.C_n);
  f.q1 = valve.q1;
  f.q2 = valve.q2;
  f.q_supply = valve.q_supply;

  // Leak sizes are stated at 40 degC; the flow follows the viscosity ratio (MODEL.md). The
  // external leak keeps its C_E: MODEL.md names C_n and C_L as the paths that scale with r.
  f.C_L = c_.r * leak_.at(leak_.ramp_s > 0.0 ? t : step_midpoint);
  f.q_int = cross_port_flow(f.C_L, p1, p2);
  if (external_leak_.C_L > 0.0) {
    const double C_E = external_leak_.at(external_leak_.ramp_s > 0.0 ? t : step_midpoint);
    if (c_.external_chamber == 1) {
      f.q_ext1 = external_leak_flow(C_E, p1, p.pt);
    } else {
      f.q_ext2 = external_leak_flow(C_E, p2, p.pt);
    }
  }
  return f;
}

void Plant::rates(double t, double u, const Vector& y, Vector& dy) noexcept {
  const Parameters& p = params_;
  // Pressures are clamped at 0: the model has no cavitation.
  const double p1 = std::max(y[kP1], 0.0);
  const double p2 = std::max(y[kP2], 0.0);
  const double x = y[kX];
  const double v = y[kV];
  const PlantFlows f = evaluate(t, step_midpoint_, y[kXs], p1, p2, noise_.at(t));

  dy[kXs] = spool_rate(u + c_.u_bias, y[kXs], p.u_max, c_.tau_spool);

  const double V1 = std::max(c_.V0 + c_.A * x, c_.V_min);
  const double V2 = std::max(c_.V0 - c_.A * x, c_.V_min);
  double beta1 = c_.beta, beta2 = c_.beta;
  if (c_.alpha > 0.0) {
    beta1 = entrained_air_bulk_modulus(c_.beta, c_.alpha, p1);
    beta2 = entrained_air_bulk_modulus(c_.beta, c_.alpha, p2);
  }
  const double inflow1 = f.q1 - f.q_int - f.q_ext1;
  const double inflow2 = f.q2 + f.q_int - f.q_ext2;
  dy[kP1] = chamber_pressure_rate(beta1, V1, inflow1, c_.A * v);
  dy[kP2] = chamber_pressure_rate(beta2, V2, inflow2, -c_.A * v);
  if (y[kP1] <= 0.0 && dy[kP1] < 0.0) dy[kP1] = 0.0;
  if (y[kP2] <= 0.0 && dy[kP2] < 0.0) dy[kP2] = 0.0;

  const double friction = c_.F_C > 0.0 ? coulomb_friction(c_.F_C, v) : 0.0;
  const double stop = end_stop_force(x, v, c_.half_stroke, p.K_stop, p.c_stop);
  dy[kX] = v;
  dy[kV] = piston_acceleration(c_.A, p1, p2, p.m, c_.b, p.K_s, x, v, friction, stop);

  // Transducer lag (effect sensor_lag): tau_s dp_m/dt = p - p_m; otherwise the transducer
  // output is the chamber pressure (copied after each step).
  dy[kP1Transducer] = c_.lag_p1 ? (p1 - y[kP1Transducer]) / c_.lag_tau_s : 0.0;
  dy[kP2Transducer] = c_.lag_p2 ? (p2 - y[kP2Transducer]) / c_.lag_tau_s : 0.0;

  if (ledger_) {
    dy[kMassIn1] = std::exp(y[kP1] / c_.beta) * inflow1;
    dy[kMassIn2] = std::exp(y[kP2] / c_.beta) * inflow2;
  } else {
    dy[kMassIn1] = dy[kMassIn2] = 0.0;
  }
  dy[kLeaked] = f.q_int;
}

void Plant::advance(double u, double t0, double dt) noexcept {
  const int substeps = std::max(1, static_cast<int>(std::lround(dt / step_)));
  const double h = dt / substeps;
  Vector k1, k2, k3, k4;
  for (int i = 0; i < substeps; ++i) {
    const double t = t0 + i * h;
    // A stepped leak switches at step boundaries: deciding by the step's midpoint keeps the
    // last stage of the step that ends at the onset from seeing it (an O(h) error otherwise).
    step_midpoint_ = t + 0.5 * h;
    rates(t, u, y_, k1);
    rates(t + 0.5 * h, u, y_ + 0.5 * h * k1, k2);
    rates(t + 0.5 * h, u, y_ + 0.5 * h * k2, k3);
    rates(t + h, u, y_ + h * k3, k4);
    y_ += (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    y_[kP1] = std::max(y_[kP1], 0.0);
    y_[kP2] = std::max(y_[kP2], 0.0);
    if (!c_.lag_p1) y_[kP1Transducer] = y_[kP1];
    if (!c_.lag_p2) y_[kP2Transducer] = y_[kP2];
  }
  store(y_);
  time_ = t0 + dt;
}

double Plant::leak_flow() const {
  return cross_port_flow(c_.r * leak_.at(time_), std::max(state_.p1, 0.0),
                         std::max(state_.p2, 0.0));
}

PlantFlows Plant::flows() const {
  return evaluate(time_, time_, state_.xs, std::max(state_.p1, 0.0), std::max(state_.p2, 0.0),
                  noise_.peek(time_));
}

}  // namespace leakmon::sim
