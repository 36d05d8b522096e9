// Piston (MODEL.md "piston"): m dv/dt = A (p1 - p2) - b v - K_s x - F_fric(v), plus the end
// stops at |x| = L/2 (stiff spring and damper acting only while in contact).
#pragma once

namespace leakmon::sim {

inline double end_stop_force(double x, double v, double half_stroke, double K_stop,
                             double c_stop) noexcept {
  if (x > half_stroke) return -K_stop * (x - half_stroke) - c_stop * v;
  if (x < -half_stroke) return -K_stop * (x + half_stroke) - c_stop * v;
  return 0.0;
}

inline double piston_acceleration(double A, double p1, double p2, double m, double b, double K_s,
                                  double x, double v, double friction, double stop) noexcept {
  return (A * (p1 - p2) - b * v - K_s * x - friction + stop) / m;
}

}  // namespace leakmon::sim
