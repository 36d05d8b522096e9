// Synthetic observation streams with known truth for the detectors' unit tests: a rig holding
// random positions against its spring, the valve command that the orifice law needs to feed a
// given cross-piston leak, and a noise-driven wavelet index that depends on the load pressure.
// (The simulator-based evaluation, tests/detect/evaluate_test.cpp, covers the real physics.)
#pragma once

#include <algorithm>
#include <cmath>
#include <random>

#include "detect/detector.hpp"
#include "detect/valve_flow.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"

namespace leakmon::test {

struct SyntheticRig {
  double hop = 0.04;
  double leak = 0.0;  // C_L [m^3/(s Pa)] from `onset` on
  double onset = 1e300;
  double null_leak = 5e-13;   // acts as a healthy cross-port leak
  double index_drop = 0.0;    // relative index drop once the leak is on
  double index_noise = 0.15;  // log-index scatter per independent window
  double kv = 3.39e-7;
  // MODEL.md's valve_bias (the valve sees u + command_offset) and valve_overlap (a dead band of
  // `overlap` of full travel). With overlap, the first `crossing_hops` of a hold on the other
  // side hold the spool inside the dead band (no flow) while the piston stands still.
  double command_offset = 0.0;  // [V]
  double overlap = 0.0;
  int crossing_hops = 0;
  double spring = 80e3, area = 6.334e-4;
  sim::Parameters valve;  // the rig table: ps, pt, u_max, dp_lin
  // Drifting conditions (MODEL.md): oil temperature [degC] at time t (laminar leaks, the null
  // leakage included, follow the viscosity ratio; leak and null_leak are stated at 40 degC),
  // reported as Observation::temp when report_temp; the supply pressure at time t, reported as
  // Observation::ps when report_supply.
  double (*temperature)(double t) = nullptr;
  sim::Oil oil = sim::Oil::standard();
  bool report_temp = false;
  double (*supply)(double t) = nullptr;
  bool report_supply = false;
  // The index follows the oil as ln(index) += index_friction_exponent * -ln(0.5 + 0.5 / r) (less
  // viscous damping of the hydraulic mode in warm oil) and the supply as sqrt(ps) (the spool
  // noise's flow); both are zero at 40 degC and the configured supply.
  double index_friction_exponent = 0.0;
  std::mt19937_64 rng{1};

  double t = 0.0;
  double hold_left = 0.0, x = 0.0, target = 0.0;
  int crossing_left = 0;
  double window_level = 0.0;  // the log-index's slowly varying part (one window memory)

  detect::Observation next() {
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    t += hop;
    hold_left -= hop;
    if (hold_left <= 0.0) {
      target = (uniform(rng) < 0.5 ? -1.0 : 1.0) * (0.025 + 0.025 * uniform(rng));
      hold_left = 0.5 + 3.5 * uniform(rng);
    }
    const double previous_x = x;
    x += std::clamp(target - x, -0.01, 0.01);  // moves at up to 0.25 m/s, then rests
    const double temp = temperature != nullptr ? temperature(t) : 40.0;
    const double r = oil.ratio(temp);
    const double leak_now = (t >= onset ? leak : 0.0) * r;
    const double dp = spring * x / area;
    sim::Parameters now = valve;
    if (supply != nullptr) now.ps = supply(t);
    const double p_mid = 0.5 * (now.ps + now.pt);
    detect::Observation o;
    o.t = t;
    o.p1 = p_mid + dp / 2 + 2e3 * normal(rng);
    o.p2 = p_mid - dp / 2 + 2e3 * normal(rng);
    o.x = x + 2e-6 * normal(rng);
    if (report_temp) o.temp = temp + 0.05 * normal(rng);
    if (report_supply) o.ps = now.ps + 5e3 * normal(rng);
    // Command whose load flow (valve_flow.hpp) feeds the leak, the null leak and the motion.
    const double flow = (leak_now + null_leak * r) * dp + area * (x - previous_x) / hop;
    const double per_opening = std::abs(detect::load_flow_per_kv(
        now, std::copysign(now.u_max, flow), p_mid + dp / 2, p_mid - dp / 2));
    const double opening = flow / (kv * per_opening);
    const bool arrived_across = x == target && previous_x != x && previous_x * x < 0.0;
    if (arrived_across) crossing_left = crossing_hops;
    const double spool = crossing_left > 0 ? 0.0 : opening + std::copysign(overlap, opening);
    if (crossing_left > 0) --crossing_left;
    o.u = valve.u_max * spool - command_offset + 1e-3 * normal(rng);
    // Index: load-dependent level, AR(1) with about one window of memory, drop after onset.
    window_level = 0.95 * window_level + std::sqrt(1 - 0.95 * 0.95) * index_noise * normal(rng);
    const double load = dp / valve.ps;
    const double drift = -index_friction_exponent * std::log(sim::friction_factor(r)) +
                         0.5 * std::log(now.ps / valve.ps);
    const double log_index = std::log(30e3) - 0.8 * load * load + 0.1 * load + window_level +
                             drift + (t >= onset ? std::log1p(-index_drop) : 0.0);
    o.index_p1 = std::exp(log_index + 0.02 * normal(rng));
    o.index_p2 = std::exp(log_index + 0.02 * normal(rng));
    o.x_activity = 0.03;
    return o;
  }
};

// What feeding a detector a stretch of the rig gave: the first hop whose score reached the raise
// threshold (-1: none), the largest score before the rig's onset, and the last decision.
struct DetectorRun {
  double first_raise = -1.0;
  double max_healthy_score = 0.0;
  detect::Decision last;
};

// Feeds the detector the rig's observations until `seconds`; healthy hops are those before the
// rig's onset.
inline DetectorRun run_detector(detect::Detector& detector, SyntheticRig& rig, double seconds) {
  DetectorRun result;
  while (rig.t < seconds) {
    const detect::Observation o = rig.next();
    result.last = detector.update(o);
    if (std::isnan(result.last.score)) continue;
    if (o.t < rig.onset) {
      result.max_healthy_score = std::max(result.max_healthy_score, result.last.score);
    }
    if (result.first_raise < 0 && result.last.score >= detector.raise_threshold()) {
      result.first_raise = o.t;
    }
  }
  return result;
}

// Drifting conditions shared by the detectors' drift tests (MODEL.md's strongest):
// a cooler cycle at working temperature, +-4 K every 5 min ...
inline double cooler(double t) {
  return 50.0 + 4.0 * std::sin(2.0 * 3.141592653589793 * t / 300.0);
}
// ... and a pump compensator turned down, 17.2 to 14 MPa over 2 s at t = 600 s, then up to
// 20 MPa at 900 s.
inline double supply_changes(double t) {
  if (t < 600.0) return 17.2e6;
  if (t < 602.0) return 17.2e6 - 3.2e6 * (t - 600.0) / 2.0;
  if (t < 900.0) return 14e6;
  if (t < 902.0) return 14e6 + 6e6 * (t - 900.0) / 2.0;
  return 20e6;
}

}  // namespace leakmon::test
