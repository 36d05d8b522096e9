// Leakage paths (MODEL.md "leakage" and effect "external_leakage"): cross-port
// q_int = C_L (p1 - p2) with C_L switched on at an onset (step or linear ramp), and a
// chamber-to-tank leak q_ext,i = C_E (p_i - pt).
#pragma once

#include <algorithm>

namespace leakmon::sim {

struct LeakSchedule {
  double C_L = 0.0;
  double onset_s = 0.0;
  double ramp_s = 0.0;

  double at(double t) const noexcept {
    if (C_L == 0.0 || t < onset_s) return 0.0;
    if (ramp_s <= 0.0) return C_L;
    return C_L * std::clamp((t - onset_s) / ramp_s, 0.0, 1.0);
  }
};

inline double cross_port_flow(double C_L, double p1, double p2) noexcept { return C_L * (p1 - p2); }

inline double external_leak_flow(double C_E, double p, double pt) noexcept {
  return C_E * (p - pt);
}

}  // namespace leakmon::sim
