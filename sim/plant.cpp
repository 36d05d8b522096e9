#include "sim/plant.hpp"

#include <algorithm>
#include <cmath>

#include "sim/friction.hpp"
#include "sim/spool.hpp"

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
  c_ = actuator_coefficients(params, effects);
  if (effects.internal_leakage) {
    leak_ = {effects.internal_leakage->C_L, effects.internal_leakage->onset_s,
             effects.internal_leakage->ramp_s};
  }
  if (effects.external_leakage) {
    external_leak_ = {effects.external_leakage->C_E, effects.external_leakage->onset_s,
                      effects.external_leakage->ramp_s};
  }
  set_conditions(kReferenceTemperature, params.ps);
  reset();
}

void Plant::set_effects(const Effects& effects) noexcept {
  effects_ = effects;
  const double ps0 = c_.ps;
  c_ = actuator_coefficients(params_, effects);
  leak_ = effects.internal_leakage
              ? LeakSchedule{effects.internal_leakage->C_L, effects.internal_leakage->onset_s,
                             effects.internal_leakage->ramp_s}
              : LeakSchedule{};
  external_leak_ = effects.external_leakage ? LeakSchedule{effects.external_leakage->C_E,
                                                           effects.external_leakage->onset_s,
                                                           effects.external_leakage->ramp_s}
                                            : LeakSchedule{};
  apply_conditions(c_, params_, oil_, temperature_, ps0);
}

void Plant::set_conditions(double oil_temperature_C, double ps0) noexcept {
  temperature_ = oil_temperature_C;
  apply_conditions(c_, params_, oil_, oil_temperature_C, ps0);
}

void Plant::set_oil(const Oil& oil) {
  oil_ = oil;
  set_conditions(temperature_, c_.ps);
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

namespace {

// A stepped schedule is read at the step's midpoint, a ramp at t (see advance()).
double scheduled(const LeakSchedule& leak, double t, double step_midpoint) noexcept {
  return leak.at(leak.ramp_s > 0.0 ? t : step_midpoint);
}

}  // namespace

PlantFlows Plant::evaluate(double t, double step_midpoint, double xs, double p1, double p2,
                           double w) const noexcept {
  const ActuatorFlows a = actuator_flows(c_, t, xs, w, scheduled(leak_, t, step_midpoint),
                                         scheduled(external_leak_, t, step_midpoint), p1, p2);
  return {a.ps, w, a.opening, a.q1, a.q2, a.q_supply, a.q_int, a.q_ext1, a.q_ext2, a.C_L};
}

void Plant::rates(double t, double spool_in, const Vector& y, Vector& dy) noexcept {
  const ActuatorRates r = actuator_rates(
      c_, t, spool_in, noise_.at(t), scheduled(leak_, t, step_midpoint_),
      scheduled(external_leak_, t, step_midpoint_), y[kXs], y[kX], y[kV], y[kP1], y[kP2]);
  dy[kXs] = r.xs;
  dy[kX] = r.x;
  dy[kV] = r.v;
  dy[kP1] = r.p1;
  dy[kP2] = r.p2;
  // Transducer lag (effect sensor_lag); otherwise the transducer output is the chamber
  // pressure (copied after each step).
  dy[kP1Transducer] =
      c_.lag_p1 ? transducer_lag_rate(r.p1_clamped, y[kP1Transducer], c_.lag_tau_s) : 0.0;
  dy[kP2Transducer] =
      c_.lag_p2 ? transducer_lag_rate(r.p2_clamped, y[kP2Transducer], c_.lag_tau_s) : 0.0;

  if (ledger_) {
    dy[kMassIn1] = std::exp(y[kP1] / c_.beta) * r.inflow1;
    dy[kMassIn2] = std::exp(y[kP2] / c_.beta) * r.inflow2;
  } else {
    dy[kMassIn1] = dy[kMassIn2] = 0.0;
  }
  dy[kLeaked] = r.q_int;
}

void Plant::advance(double u, double t0, double dt) noexcept {
  const int substeps = std::max(1, static_cast<int>(std::lround(dt / step_)));
  const double h = dt / substeps;
  const double spool_in = spool_command(u + c_.u_bias, params_.u_max);
  Vector k1, k2, k3, k4;
  for (int i = 0; i < substeps; ++i) {
    const double t = t0 + i * h;
    // A stepped leak switches at step boundaries: deciding by the step's midpoint keeps the
    // last stage of the step that ends at the onset from seeing it (an O(h) error otherwise).
    step_midpoint_ = t + 0.5 * h;
    rates(t, spool_in, y_, k1);
    rates(t + 0.5 * h, spool_in, y_ + 0.5 * h * k1, k2);
    rates(t + 0.5 * h, spool_in, y_ + 0.5 * h * k2, k3);
    rates(t + h, spool_in, y_ + h * k3, k4);
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
  return cross_port_flow(internal_leak_coefficient(c_, leak_.at(time_)), std::max(state_.p1, 0.0),
                         std::max(state_.p2, 0.0));
}

PlantFlows Plant::flows() const {
  return evaluate(time_, time_, state_.xs, std::max(state_.p1, 0.0), std::max(state_.p2, 0.0),
                  noise_.peek(time_));
}

}  // namespace leakmon::sim
