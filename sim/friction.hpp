// Friction on the piston: viscous b v (MODEL.md "piston") and the effect library's Coulomb
// friction F_C tanh(v / 1e-3), smooth so that a fixed-step integrator can cross v = 0.
#pragma once

#include <cmath>

namespace leakmon::sim {

inline constexpr double kCoulombVelocityScale = 1e-3;  // m/s

// velocity_scale > 1e-3 widens the sticking band where a fixed step cannot resolve the tanh
// (the model check's coarse steps); the force outside the band is unchanged.
inline double coulomb_friction(double F_C, double v,
                               double velocity_scale = kCoulombVelocityScale) noexcept {
  return F_C * std::tanh(v / velocity_scale);
}

}  // namespace leakmon::sim
