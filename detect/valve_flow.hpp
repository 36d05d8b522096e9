// The servovalve's orifice law (MODEL.md "valve"), used to turn a command and the chamber
// pressures into the flow the valve delivers, in units of the unknown valve coefficient Kv.
#pragma once

#include <algorithm>
#include <cmath>

namespace leakmon::detect {

struct ValveGeometry {
  double supply_pressure = 17.2e6;   // ps [Pa]
  double tank_pressure = 0.1e6;      // pt [Pa]
  double command_full_scale = 10.0;  // u_max [V]
  double laminar_threshold = 2e5;    // dp_lin [Pa]
};

// sign(dp) sqrt(|dp|), linearised below dp_lin as the model does (laminar near zero).
inline double signed_root(double dp, double dp_lin) {
  if (std::abs(dp) >= dp_lin) return std::copysign(std::sqrt(std::abs(dp)), dp);
  return dp / std::sqrt(dp_lin);
}

// Load flow (q1 - q2) / 2 divided by Kv [sqrt(Pa)]: the mean of what the valve sends into
// chamber 1 and takes out of chamber 2. Averaging the two chambers cancels most of the
// compressibility flow and anything that moves p1 + p2.
inline double load_flow_per_kv(const ValveGeometry& valve, double u, double p1, double p2) {
  const double opening = std::clamp(u / valve.command_full_scale, -1.0, 1.0);
  const double ps = valve.supply_pressure, pt = valve.tank_pressure, lin = valve.laminar_threshold;
  const double into_1 =
      opening >= 0.0 ? opening * signed_root(ps - p1, lin) : opening * signed_root(p1 - pt, lin);
  const double out_of_2 =
      opening >= 0.0 ? opening * signed_root(p2 - pt, lin) : opening * signed_root(ps - p2, lin);
  return 0.5 * (into_1 + out_of_2);
}

}  // namespace leakmon::detect
