// Chamber continuity (MODEL.md "volumes", "pressures"):
//   V1 = V0 + A x, V2 = V0 - A x,  dp_i/dt = beta_e(p_i) / V_i * (net inflow - dV_i/dt)
// with beta_e = beta, or the Simscape Fluids entrained-air law (effect "entrained_air").
#pragma once

#include <algorithm>
#include <cmath>

namespace leakmon::sim {

inline constexpr double kAtmosphere = 101325.0;  // p_a [Pa]
inline constexpr double kPolytropic = 1.4;       // n

// beta_e(p) = E_l (1 + alpha (p_a/(p_a+p))^(1/n)) / (1 + alpha p_a^(1/n) E_l / (n
// (p_a+p)^((n+1)/n)))
// One pow() per call: (p_a/p)^(1/n) = p_a^(1/n) / p^(1/n) and p^((n+1)/n) = p p^(1/n). Inside
// the model check's fits this law runs twice per derivative evaluation, and two pow() calls
// were 13 % of a 180 s check with the entrained-air candidate (model_check_bench).
inline double entrained_air_bulk_modulus(double E_l, double alpha, double p_gauge) noexcept {
  const double p_abs = kAtmosphere + std::max(p_gauge, 0.0);
  const double atmosphere_root = std::pow(kAtmosphere, 1.0 / kPolytropic);  // folded: constants
  const double root = std::pow(p_abs, 1.0 / kPolytropic);
  const double numerator = 1.0 + alpha * atmosphere_root / root;
  const double denominator = 1.0 + alpha * atmosphere_root * E_l / (kPolytropic * p_abs * root);
  return E_l * numerator / denominator;
}

// The bulk modulus in force: beta itself without entrained air (alpha = 0).
inline double bulk_modulus(double beta, double alpha, double p_gauge) noexcept {
  return alpha > 0.0 ? entrained_air_bulk_modulus(beta, alpha, p_gauge) : beta;
}

// dp/dt of one chamber: bulk modulus, volume, net port inflow, volume growth rate.
inline double chamber_pressure_rate(double bulk_modulus, double volume, double inflow,
                                    double volume_rate) noexcept {
  return bulk_modulus / volume * (inflow - volume_rate);
}

}  // namespace leakmon::sim
