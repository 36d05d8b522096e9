#include "model/actuator_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace leakmon::model {
namespace {

constexpr int kMaxSubsteps = 16;  // per sample: bounds the cost of stiff friction

sim::Parameters calibrated(sim::Parameters rig, const Calibration& c) {
  rig.beta = c.beta;
  rig.Kv = c.Kv;
  rig.m = c.m;
  rig.b = c.b;
  return rig;
}

// An oil with ISO VG 46's viscosity at 40 degC whose Walther line has the viscosity slope
// `slope` at 40 degC (the slope grows as the 100 degC viscosity falls): bisection on nu(100).
sim::Oil oil_with_slope(double slope) {
  const double nu40 = 46.0;
  double thin = 1.0, thick = 0.95 * nu40;  // slope(thin) > slope(thick)
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (thin + thick);
    if (sim::Oil(nu40, mid).viscosity_slope(sim::kReferenceTemperature) > slope) {
      thin = mid;
    } else {
      thick = mid;
    }
  }
  return sim::Oil(nu40, 0.5 * (thin + thick));
}

}  // namespace

ActuatorModel::ActuatorModel(const ModelParameters& parameters, const sim::Parameters& rig)
    : parameters_(parameters),
      rig_(calibrated(rig, parameters.calibration)),
      c_(sim::actuator_coefficients(rig_, {})) {
  // The effect parameters straight into the shared coefficients: an effect that is off has the
  // value that makes its term vanish, as in sim::actuator_coefficients.
  const auto& e = parameters.effects;
  if (e.spool_tau > 0.0) c_.tau_spool = e.spool_tau;
  c_.u_bias = e.u0;
  c_.overlap = e.d;
  c_.ripple_dP = e.ripple_dP;
  c_.ripple_dQ = e.ripple_dQ;
  c_.ripple_omega = 2.0 * std::numbers::pi * e.ripple_f;
  c_.droop_R_s = e.R_s;
  c_.C_E = e.C_E;
  c_.external_chamber = e.external_chamber;
  c_.F_C = e.F_C;
  c_.alpha = e.alpha;
  if (e.visc_slope > 0.0) oil_ = oil_with_slope(e.visc_slope);
  lagging_ = e.tau_s > 0.0;
  if (lagging_) {
    c_.lag_tau_s = e.tau_s;
    c_.lag_p1 = e.lag_channel == PressureChannel::p1;
    c_.lag_p2 = !c_.lag_p1;
  }
  fastest_rate_ = fastest_rate(true);
  fastest_rate_without_friction_ = fastest_rate(false);
}

double ActuatorModel::fastest_rate(bool with_friction) const {
  // Largest real eigenvalue magnitudes: friction damping, spool, lagging transducer.
  const double friction = with_friction ? std::abs(c_.F_C) / sim::kCoulombVelocityScale : 0.0;
  double rate = (friction + c_.b) / c_.m;
  rate = std::max(rate, 1.0 / c_.tau_spool);
  if (lagging_) rate = std::max(rate, 1.0 / c_.lag_tau_s);
  // Laminar orifice and hydraulic stiffness at the smallest chamber (|x| <= L/4 in practice).
  const double volume = c_.V0 - c_.A * rig_.L / 4.0;
  rate = std::max(rate, c_.beta / volume * c_.Kv / std::sqrt(c_.dp_lin));
  rate = std::max(rate, std::sqrt(c_.beta * 2.0 * c_.A * c_.A / (volume * c_.m)));
  return rate;
}

int ActuatorModel::substeps_at_rate(double rate, double dt) {
  constexpr double kStableStep = 2.0;  // RK4 is stable up to |lambda| dt = 2.78
  return std::clamp(static_cast<int>(std::ceil(rate * dt / kStableStep)), 4, kMaxSubsteps);
}

int ActuatorModel::substeps(double dt) const { return substeps_at_rate(fastest_rate_, dt); }

double ActuatorModel::friction_velocity(double h) const {
  // Where even kMaxSubsteps cannot keep tanh(v / 1e-3) stable, the sticking band is widened
  // just enough (|lambda| h = 2): the force outside the band is unchanged, inside it the
  // piston still sticks, far harder than the viscous friction b could hold it.
  return std::max(sim::kCoulombVelocityScale, std::abs(c_.F_C) * h / (2.0 * c_.m));
}

double ActuatorModel::spool_input(double u) const {
  return sim::spool_command(u + c_.u_bias, c_.u_max);
}

// Always inlined into advance(), its one caller, four times per sub-step: GCC kept it out of
// line, each call passing the state and its rates through memory (model_check_bench's
// BM_FittingResiduals 3.3 -> 2.6 ms inlined, the same numbers).
[[gnu::always_inline]] inline ActuatorState ActuatorModel::derivative(
    const sim::ActuatorCoefficients& c, const ActuatorState& s, double spool_in, double w,
    double t) const {
  const sim::ActuatorRates r = sim::actuator_rates(c, t, spool_in, w, parameters_.effects.C_L,
                                                   c.C_E, s.xs, s.x, s.v, s.p1, s.p2);
  ActuatorState d{r.xs, r.x, r.v, r.p1, r.p2, 0.0};
  if (lagging_) {
    d.s = sim::transducer_lag_rate(c.lag_p1 ? r.p1_clamped : r.p2_clamped, s.s, c.lag_tau_s);
  }
  return d;
}

namespace {

ActuatorState axpy(const ActuatorState& a, double h, const ActuatorState& d) {
  return {a.xs + h * d.xs, a.x + h * d.x,   a.v + h * d.v,
          a.p1 + h * d.p1, a.p2 + h * d.p2, a.s + h * d.s};
}

}  // namespace

sim::ActuatorCoefficients ActuatorModel::coefficients_at(double T) const {
  sim::ActuatorCoefficients c = c_;
  sim::apply_conditions(c, rig_, oil_, T, rig_.ps);
  return c;
}

void ActuatorModel::advance(ActuatorState& state, double u, double t0, double dt, double w) const {
  advance(state, u, t0, dt, w, c_);
}

// The force on the piston other than friction, as a share of F_C: below 1 in magnitude the
// piston sticks (F_C tanh(v / 1e-3) can hold it), above it slides.
inline double ActuatorModel::stick_ratio(const sim::ActuatorCoefficients& c,
                                         const ActuatorState& s) {
  const double p1 = std::max(s.p1, 0.0);
  const double p2 = std::max(s.p2, 0.0);
  const double stop = sim::end_stop_force(s.x, s.v, c.half_stroke, c.K_stop, c.c_stop);
  return (c.A * (p1 - p2) - c.K_s * s.x + stop) / c.F_C;
}

// Where the stiff velocity equation relaxes to within ~1/lambda: F_C tanh(v / v_f) + b v = the
// force, i.e. v_f atanh(ratio) with one Newton step for the small viscous term.
inline double ActuatorModel::sticking_velocity(const sim::ActuatorCoefficients& c, double ratio) {
  const double r = std::clamp(ratio, -kMaxStickRatio, kMaxStickRatio);
  const double v0 = c.friction_velocity * 0.5 * std::log((1.0 + r) / (1.0 - r));  // atanh
  const double slope = c.F_C * (1.0 - r * r) / c.friction_velocity + c.b;
  return v0 - c.b * v0 / slope;
}

// Stuck: the piston's velocity slaved to the force (the singular-perturbation limit of the
// sticking phase); the other states move as usual.
template <bool kStuck>
[[gnu::always_inline]] inline ActuatorState ActuatorModel::rate(const sim::ActuatorCoefficients& c,
                                                                const ActuatorState& s,
                                                                double spool_in, double w,
                                                                double t) const {
  if constexpr (!kStuck) {
    return derivative(c, s, spool_in, w, t);
  } else {
    ActuatorState slaved = s;
    slaved.v = sticking_velocity(c, stick_ratio(c, s));
    ActuatorState d = derivative(c, slaved, spool_in, w, t);
    d.v = 0.0;
    return d;
  }
}

template <bool kStuck>
[[gnu::always_inline]] inline void ActuatorModel::rk4_step(ActuatorState& state,
                                                           const sim::ActuatorCoefficients& c,
                                                           double spool_in, double t, double h,
                                                           double w) const {
  const ActuatorState k1 = rate<kStuck>(c, state, spool_in, w, t);
  const ActuatorState k2 = rate<kStuck>(c, axpy(state, h / 2, k1), spool_in, w, t + h / 2);
  const ActuatorState k3 = rate<kStuck>(c, axpy(state, h / 2, k2), spool_in, w, t + h / 2);
  const ActuatorState k4 = rate<kStuck>(c, axpy(state, h, k3), spool_in, w, t + h);
  state.xs += h / 6 * (k1.xs + 2 * k2.xs + 2 * k3.xs + k4.xs);
  state.x += h / 6 * (k1.x + 2 * k2.x + 2 * k3.x + k4.x);
  state.v += h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v);
  state.p1 += h / 6 * (k1.p1 + 2 * k2.p1 + 2 * k3.p1 + k4.p1);
  state.p2 += h / 6 * (k1.p2 + 2 * k2.p2 + 2 * k3.p2 + k4.p2);
  state.s += h / 6 * (k1.s + 2 * k2.s + 2 * k3.s + k4.s);
  // No cavitation model (MODEL.md): pressures are clamped at zero.
  state.p1 = std::max(state.p1, 0.0);
  state.p2 = std::max(state.p2, 0.0);
}

// Coulomb friction on a light piston is a damper of rate F_C / (1e-3 m) far beyond what the
// sub-steps resolve (71 000 1/s for 265 N on 3.7 kg). Widening the band to fit the step let
// the piston creep several times too fast while it should stick, and the true friction fitted
// worse than none (docs/model-check.md). So each sub-step either slides (the full equations:
// the tanh is flat outside the band) or, while the force cannot break the piston free and it
// is inside the band, sticks: its velocity is the one F_C tanh(v / 1e-3) balances, and only
// the other states are integrated. A sliding step that ends stopped (the velocity through
// zero or into the band) under a force friction holds is put onto that velocity.
void ActuatorModel::advance_sticking(ActuatorState& state, double spool_in, double t0, double h,
                                     int n, double w, const sim::ActuatorCoefficients& c) const {
  const double band = c.friction_velocity * std::atanh(kMaxStickRatio);
  for (int i = 0; i < n; ++i) {
    const double t = t0 + i * h;
    const bool holds = std::abs(stick_ratio(c, state)) < kMaxStickRatio;
    if (holds && std::abs(state.v) <= band) {
      rk4_step<true>(state, c, spool_in, t, h, w);
      state.v = sticking_velocity(c, stick_ratio(c, state));
      continue;
    }
    const double v_before = state.v;
    rk4_step<false>(state, c, spool_in, t, h, w);
    const bool stopped = state.v * v_before <= 0.0 || std::abs(state.v) <= band;
    if (stopped) {
      const double ratio = stick_ratio(c, state);
      if (std::abs(ratio) < kMaxStickRatio) state.v = sticking_velocity(c, ratio);
    }
  }
}

void ActuatorModel::advance(ActuatorState& state, double u, double t0, double dt, double w,
                            const sim::ActuatorCoefficients& base) const {
  const double spool_in = spool_input(u);
  const int n = substeps(dt);
  const double h = dt / n;
  if (base.F_C > 0.0 && friction_velocity(h) != base.friction_velocity) {
    // Sticking takes the friction's stiffness out of the steps: the other rates set them.
    const int n_sticking = substeps_at_rate(fastest_rate_without_friction_, dt);
    advance_sticking(state, spool_in, t0, dt / n_sticking, n_sticking, w, base);
    return;
  }
  // A negative F_C (a fit's trial) is no sticking force: the band widened just enough instead
  // (a copy of the coefficients, so the shared rates stay the only place the equations live).
  const sim::ActuatorCoefficients* c = &base;
  sim::ActuatorCoefficients widened;
  if (base.F_C != 0.0) {
    const double v_fric = friction_velocity(h);
    if (v_fric != base.friction_velocity) {
      widened = base;
      widened.friction_velocity = v_fric;
      c = &widened;
    }
  }
  for (int i = 0; i < n; ++i) rk4_step<false>(state, *c, spool_in, t0 + i * h, h, w);
}

Reading ActuatorModel::read(const ActuatorState& state) const {
  const auto& e = parameters_.effects;
  Reading r{state.x, state.p1, state.p2};
  if (lagging_) (c_.lag_p1 ? r.p1 : r.p2) = state.s;
  if (e.offset != 0.0) (e.offset_channel == PressureChannel::p1 ? r.p1 : r.p2) += e.offset;
  return r;
}

}  // namespace leakmon::model
