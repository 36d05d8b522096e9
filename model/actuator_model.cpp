#include "model/actuator_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace leakmon::model {
namespace {

constexpr double kAtmosphere = 101325.0;    // p_a of the entrained-air law
constexpr double kPolytropic = 1.4;         // n
constexpr double kFrictionVelocity = 1e-3;  // tanh(v / 1e-3) of coulomb_friction
constexpr int kMaxSubsteps = 16;            // per sample: bounds the cost of stiff friction

// MODEL.md's orifice law sg(dp): turbulent sqrt, laminar (linear) below dp_lin.
double orifice(double dp, double dp_lin) {
  if (std::abs(dp) >= dp_lin) return std::copysign(std::sqrt(std::abs(dp)), dp);
  return dp / std::sqrt(dp_lin);
}

double orifice_slope(double dp, double dp_lin) {
  if (std::abs(dp) >= dp_lin) return 0.5 / std::sqrt(std::abs(dp));
  return 1.0 / std::sqrt(dp_lin);
}

}  // namespace

ActuatorModel::ActuatorModel(const ModelParameters& parameters, const RigConstants& rig)
    : parameters_(parameters),
      rig_(rig),
      spool_tau_(parameters.effects.spool_tau > 0.0 ? parameters.effects.spool_tau : rig.spool_tau),
      half_volume_(rig.half_volume()) {}

int ActuatorModel::substeps(double dt) const {
  const auto& c = parameters_.calibration;
  // Largest real eigenvalue magnitudes: friction damping, spool, lagging transducer.
  double rate = (std::abs(parameters_.effects.F_C) / kFrictionVelocity + c.b) / c.m;
  rate = std::max(rate, 1.0 / spool_tau_);
  if (parameters_.effects.tau_s > 0.0) rate = std::max(rate, 1.0 / parameters_.effects.tau_s);
  // Laminar orifice and hydraulic stiffness at the smallest chamber (|x| <= L/4 in practice).
  const double volume = half_volume_ - rig_.area * rig_.stroke / 4.0;
  rate = std::max(rate, c.beta / volume * c.Kv / std::sqrt(rig_.laminar_threshold));
  rate = std::max(rate, std::sqrt(c.beta * 2.0 * rig_.area * rig_.area / (volume * c.m)));
  constexpr double kStableStep = 2.0;  // RK4 is stable up to |lambda| dt = 2.78
  return std::clamp(static_cast<int>(std::ceil(rate * dt / kStableStep)), 4, kMaxSubsteps);
}

double ActuatorModel::friction_velocity(double h) const {
  // Where even kMaxSubsteps cannot keep tanh(v / 1e-3) stable, the sticking band is widened
  // just enough (|lambda| h = 2): the force outside the band is unchanged, inside it the
  // piston still sticks, far harder than the viscous friction b could hold it.
  const auto& c = parameters_.calibration;
  return std::max(kFrictionVelocity, std::abs(parameters_.effects.F_C) * h / (2.0 * c.m));
}

double ActuatorModel::spool_input(double u) const {
  return std::clamp((u + parameters_.effects.u0) / rig_.command_full_scale, -1.0, 1.0);
}

double ActuatorModel::opening(double xs) const {
  const double d = parameters_.effects.d;
  if (d <= 0.0) return xs;
  return std::copysign(std::max(std::abs(xs) - d, 0.0), xs);
}

double ActuatorModel::bulk_modulus(double p) const {
  const double beta = parameters_.calibration.beta;
  const double alpha = parameters_.effects.alpha;
  if (alpha <= 0.0) return beta;
  const double pa = kAtmosphere;
  const double pabs = pa + std::max(p, 0.0);
  const double num = 1.0 + alpha * std::pow(pa / pabs, 1.0 / kPolytropic);
  const double den = 1.0 + alpha * std::pow(pa, 1.0 / kPolytropic) * beta /
                               (kPolytropic * std::pow(pabs, (kPolytropic + 1.0) / kPolytropic));
  return beta * num / den;
}

double ActuatorModel::supply_pressure(double t, double o, double p1, double p2) const {
  const auto& e = parameters_.effects;
  double ps = rig_.supply_pressure;
  if (e.ripple_f > 0.0) {
    const double phase = 2.0 * std::numbers::pi * e.ripple_f * t;
    ps += e.ripple_dP * std::sin(phase) + e.ripple_dQ * std::cos(phase);
  }
  if (e.R_s <= 0.0) return ps;
  // ps = ps_r - R_s q_s(ps): q_s grows with ps, so g(ps) = ps - ps_r + R_s q_s(ps) is
  // increasing and Newton's method from ps_r converges in a few steps.
  const double kv = parameters_.calibration.Kv;
  const double cn = rig_.null_leakage;
  const double dp_lin = rig_.laminar_threshold;
  const double p_open = o >= 0.0 ? p1 : p2;
  const double ps_r = ps;
  for (int i = 0; i < 8; ++i) {
    const double q = kv * std::abs(o) * orifice(ps - p_open, dp_lin) + cn * ((ps - p1) + (ps - p2));
    const double dq = kv * std::abs(o) * orifice_slope(ps - p_open, dp_lin) + 2.0 * cn;
    const double g = ps - ps_r + e.R_s * q;
    const double step = g / (1.0 + e.R_s * dq);
    ps -= step;
    if (std::abs(step) < 1.0) break;
  }
  return ps;
}

ActuatorState ActuatorModel::derivative(const ActuatorState& s, double spool_in, double t,
                                        double v_fric) const {
  const auto& c = parameters_.calibration;
  const auto& e = parameters_.effects;
  const auto& r = rig_;
  const double dp_lin = r.laminar_threshold;
  const double o = opening(s.xs);
  const double ps = supply_pressure(t, o, s.p1, s.p2);
  const double pt = r.tank_pressure;

  double q1 = 0.0;
  double q2 = 0.0;
  if (o >= 0.0) {
    q1 = c.Kv * o * orifice(ps - s.p1, dp_lin);
    q2 = -c.Kv * o * orifice(s.p2 - pt, dp_lin);
  } else {
    q1 = c.Kv * o * orifice(s.p1 - pt, dp_lin);
    q2 = -c.Kv * o * orifice(ps - s.p2, dp_lin);
  }
  q1 += r.null_leakage * ((ps - s.p1) - (s.p1 - pt));
  q2 += r.null_leakage * ((ps - s.p2) - (s.p2 - pt));
  const double q_int = e.C_L * (s.p1 - s.p2);
  const double q_ext1 = e.external_chamber == 1 ? e.C_E * (s.p1 - pt) : 0.0;
  const double q_ext2 = e.external_chamber == 2 ? e.C_E * (s.p2 - pt) : 0.0;

  const double v1 = half_volume_ + r.area * s.x;
  const double v2 = half_volume_ - r.area * s.x;

  ActuatorState d;
  d.xs = (spool_in - s.xs) / spool_tau_;
  d.x = s.v;
  d.p1 = bulk_modulus(s.p1) / v1 * (q1 - r.area * s.v - q_int - q_ext1);
  d.p2 = bulk_modulus(s.p2) / v2 * (q2 + r.area * s.v + q_int - q_ext2);
  double force = r.area * (s.p1 - s.p2) - c.b * s.v - r.spring * s.x;
  if (e.F_C != 0.0) force -= e.F_C * std::tanh(s.v / v_fric);
  const double half_stroke = r.stroke / 2.0;
  if (std::abs(s.x) > half_stroke) {
    force -=
        r.end_stop_stiffness * (s.x - std::copysign(half_stroke, s.x)) + r.end_stop_damping * s.v;
  }
  d.v = force / c.m;
  if (e.tau_s > 0.0) {
    const double p = e.lag_channel == PressureChannel::p1 ? s.p1 : s.p2;
    d.s = (p - s.s) / e.tau_s;
  }
  return d;
}

namespace {

ActuatorState axpy(const ActuatorState& a, double h, const ActuatorState& d) {
  return {a.xs + h * d.xs, a.x + h * d.x,   a.v + h * d.v,
          a.p1 + h * d.p1, a.p2 + h * d.p2, a.s + h * d.s};
}

}  // namespace

void ActuatorModel::advance(ActuatorState& state, double u, double t0, double dt) const {
  const double spool_in = spool_input(u);
  const int n = substeps(dt);
  const double h = dt / n;
  const double v_fric = friction_velocity(h);
  for (int i = 0; i < n; ++i) {
    const double t = t0 + i * h;
    const ActuatorState k1 = derivative(state, spool_in, t, v_fric);
    const ActuatorState k2 = derivative(axpy(state, h / 2, k1), spool_in, t + h / 2, v_fric);
    const ActuatorState k3 = derivative(axpy(state, h / 2, k2), spool_in, t + h / 2, v_fric);
    const ActuatorState k4 = derivative(axpy(state, h, k3), spool_in, t + h, v_fric);
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
}

Reading ActuatorModel::read(const ActuatorState& state) const {
  const auto& e = parameters_.effects;
  Reading r{state.x, state.p1, state.p2};
  if (e.tau_s > 0.0) (e.lag_channel == PressureChannel::p1 ? r.p1 : r.p2) = state.s;
  if (e.offset != 0.0) (e.offset_channel == PressureChannel::p1 ? r.p1 : r.p2) += e.offset;
  return r;
}

}  // namespace leakmon::model
