// Oil viscosity against temperature (MODEL.md "Drifting operating conditions"): Walther's
// equation (ASTM D341) through the two viscosities of the oil's data sheet,
//   log10(log10(nu + 0.7)) = A - B log10(T + 273.15),
// and the viscosity ratio r = nu(40 degC) / nu(T) that the laminar leak paths, the viscous
// friction and (through T directly) the bulk modulus of the plant follow.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace leakmon::sim {

// MODEL.md's nominal values hold at this oil temperature [degC].
inline constexpr double kReferenceTemperature = 40.0;

class Oil {
 public:
  // Data-sheet kinematic viscosities [mm^2/s] at 40 and 100 degC; nu40 > nu100 > 0.
  // Throws std::invalid_argument otherwise.
  Oil(double nu40, double nu100, std::string name = "");

  // ISO VG 32, 46 (MODEL.md's default), 68; nullopt for another grade.
  static std::optional<Oil> iso_vg(int grade);
  static Oil standard() { return *iso_vg(46); }

  double nu40() const { return nu40_; }
  double nu100() const { return nu100_; }
  const std::string& name() const { return name_; }  // "ISO VG 46", or "" when custom
  double walther_A() const { return A_; }
  double walther_B() const { return B_; }

  // Kinematic viscosity [mm^2/s] at T [degC] by Walther's equation.
  double nu(double T) const noexcept;
  // r = nu(40) / nu(T), with nu(40) evaluated by the same equation, so that r(40) is exactly 1
  // and a rig at 40 degC is bit-identical to one without temperature.
  double ratio(double T) const noexcept;
  // -d ln(nu) / dT at T [1/K] (MODEL.md's table quotes it at 40 degC).
  double viscosity_slope(double T) const noexcept;

 private:
  double nu40_, nu100_;
  std::string name_;
  double A_, B_;
  double nu_reference_;  // nu(40) from the fitted equation
};

// The temperature laws of the plant's coefficients (MODEL.md):
//   C_n, C_L -> r C_n, r C_L;  b -> b (0.5 + 0.5 / r);  beta -> beta (1 - 0.003 (T - 40)).
inline double friction_factor(double r) noexcept { return 0.5 + 0.5 / r; }
inline double bulk_modulus_factor(double T) noexcept {
  return 1.0 - 0.003 * (T - kReferenceTemperature);
}

}  // namespace leakmon::sim
