// The units a rig engineer reads (l/min, MPa) against the SI units leakmon computes in. One
// place, so that a leak size means the same in an alarm, /status, /metrics, the page and a
// scenario file.
#pragma once

namespace leakmon::units {

// 1 l/min = 1/60000 m^3/s.
inline constexpr double kLitresPerMinutePerCubicMetrePerSecond = 60000.0;
inline constexpr double kPascalPerMegapascal = 1e6;

// A flow: m^3/s -> l/min.
constexpr double litres_per_minute(double cubic_metres_per_second) {
  return cubic_metres_per_second * kLitresPerMinutePerCubicMetrePerSecond;
}

// A leak coefficient C_L: m^3/(s Pa) -> l/min/MPa, and back.
constexpr double lpm_per_mpa(double cubic_metres_per_second_pascal) {
  return cubic_metres_per_second_pascal * kLitresPerMinutePerCubicMetrePerSecond *
         kPascalPerMegapascal;
}
constexpr double cubic_metres_per_second_pascal(double lpm_per_mpa) {
  return lpm_per_mpa / (kLitresPerMinutePerCubicMetrePerSecond * kPascalPerMegapascal);
}

}  // namespace leakmon::units
