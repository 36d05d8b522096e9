// Spool (MODEL.md "spool"): tau dxs/dt = sat(u / u_max) - xs, first order, normalised -1..1.
// valve_bias shifts the command the valve sees before this saturation; spool_lag replaces tau.
#pragma once

#include <algorithm>

namespace leakmon::sim {

inline double spool_rate(double u_seen, double xs, double u_max, double tau) noexcept {
  const double command = std::clamp(u_seen / u_max, -1.0, 1.0);
  return (command - xs) / tau;
}

}  // namespace leakmon::sim
