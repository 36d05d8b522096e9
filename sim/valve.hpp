// Critically centred 4-way valve (MODEL.md "orifice", "valve", "null leak"), with the
// valve_overlap dead band of the effect library.
#pragma once

#include <algorithm>
#include <cmath>

namespace leakmon::sim {

// Regularised orifice law: sign(dp) sqrt(|dp|), laminar dp / sqrt(dp_lin) below dp_lin so the
// flow gain stays finite at zero pressure drop.
inline double orifice(double dp, double dp_lin) noexcept {
  if (std::abs(dp) >= dp_lin) return std::copysign(std::sqrt(std::abs(dp)), dp);
  return dp / std::sqrt(dp_lin);
}

// d orifice(dp) / d dp: the slope Newton's method needs for the supply droop (supply.hpp).
inline double orifice_slope(double dp, double dp_lin) noexcept {
  const double magnitude = std::abs(dp);
  if (magnitude >= dp_lin) return 0.5 / std::sqrt(magnitude);
  return 1.0 / std::sqrt(dp_lin);
}

// valve_overlap: opening sign(o) max(|o| - d, 0), deliberately not rescaled (MODEL.md).
inline double overlapped_opening(double o, double d) noexcept {
  return std::copysign(std::max(std::abs(o) - d, 0.0), o);
}

struct ValveFlows {
  double q1, q2;    // into chamber 1 and 2 [m^3/s]
  double q_supply;  // out of the supply port [m^3/s]
};

// o >= 0: supply -> 1, 2 -> tank; o < 0: 1 -> tank, supply -> 2. Null leakage: each land
// leaks laminarly, C_n (ps - p_i) in from supply and C_n (p_i - pt) out to tank. Always
// inlined: inside the shared rates (sim/actuator.hpp) GCC's size heuristics otherwise keep it
// out of line, a call per derivative evaluation (callgrind: +4 % instructions per Rig step).
[[gnu::always_inline]] inline ValveFlows valve_flows(double o, double ps, double pt, double p1,
                                                     double p2, double Kv, double dp_lin,
                                                     double C_n) noexcept {
  ValveFlows f{};
  if (o >= 0.0) {
    const double from_supply = Kv * o * orifice(ps - p1, dp_lin);
    f.q1 = from_supply;
    f.q2 = -Kv * o * orifice(p2 - pt, dp_lin);
    f.q_supply = from_supply;
  } else {
    f.q1 = Kv * o * orifice(p1 - pt, dp_lin);
    const double from_supply = -Kv * o * orifice(ps - p2, dp_lin);
    f.q2 = from_supply;
    f.q_supply = from_supply;
  }
  f.q1 += C_n * ((ps - p1) - (p1 - pt));
  f.q2 += C_n * ((ps - p2) - (p2 - pt));
  f.q_supply += C_n * ((ps - p1) + (ps - p2));
  return f;
}

}  // namespace leakmon::sim
