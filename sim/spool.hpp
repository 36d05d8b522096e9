// Spool (MODEL.md "spool"): tau dxs/dt = sat(u / u_max) - xs, first order, normalised -1..1.
// valve_bias shifts the command the valve sees before this saturation; spool_lag replaces tau.
#pragma once

#include <algorithm>

namespace leakmon::sim {

// sat(u / u_max): the spool's normalised command, also the steady-state opening.
inline double spool_command(double u_seen, double u_max) noexcept {
  return std::clamp(u_seen / u_max, -1.0, 1.0);
}

inline double spool_rate(double u_seen, double xs, double u_max, double tau) noexcept {
  return (spool_command(u_seen, u_max) - xs) / tau;
}

}  // namespace leakmon::sim
