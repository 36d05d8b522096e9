#include "sim/conditions.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace leakmon::sim {

std::string_view to_string(TemperatureProfile::Kind kind) {
  switch (kind) {
    case TemperatureProfile::Kind::constant:
      return "constant";
    case TemperatureProfile::Kind::warm_up:
      return "warm_up";
    case TemperatureProfile::Kind::cooler:
      return "cooler";
    case TemperatureProfile::Kind::warm_up_cooler:
      return "warm_up_cooler";
  }
  return "constant";
}

double TemperatureProfile::at(double t) const noexcept {
  if (kind == Kind::constant) return T_work;
  double T = T_work;
  if (kind == Kind::warm_up || kind == Kind::warm_up_cooler) {
    T = t < start_s ? T0 : T_work + (T0 - T_work) * std::exp(-(t - start_s) / tau_s);
  }
  if ((kind == Kind::cooler || kind == Kind::warm_up_cooler) && t >= cooler_start_s) {
    T += amplitude * std::sin(2.0 * std::numbers::pi * (t - cooler_start_s) / period_s);
  }
  return T;
}

double TemperatureProfile::minimum() const {
  switch (kind) {
    case Kind::constant:
      return T_work;
    case Kind::warm_up:
      return std::min(T0, T_work);
    case Kind::cooler:
      return T_work - amplitude;
    case Kind::warm_up_cooler:
      return std::min(T0, T_work) - amplitude;
  }
  return T_work;
}

std::string TemperatureProfile::describe() const {
  switch (kind) {
    case Kind::constant:
      return fmt::format("constant T={:g}", T_work);
    case Kind::warm_up:
      return fmt::format("warm_up T0={:g} T_work={:g} tau_s={:g} start_s={:g}", T0, T_work, tau_s,
                         start_s);
    case Kind::cooler:
      return fmt::format(
          "cooler T_work={:g} amplitude={:g} period_s={:g} cooler_start_s={:g} "
          "shape=sinusoidal",
          T_work, amplitude, period_s, cooler_start_s);
    case Kind::warm_up_cooler:
      return fmt::format(
          "warm_up_cooler T0={:g} T_work={:g} tau_s={:g} start_s={:g} amplitude={:g} "
          "period_s={:g} cooler_start_s={:g} shape=sinusoidal",
          T0, T_work, tau_s, start_s, amplitude, period_s, cooler_start_s);
  }
  return {};
}

double supply_setpoint(double ps_nominal, const std::vector<SupplyChange>& changes,
                       double t) noexcept {
  double ps = ps_nominal;
  for (const SupplyChange& change : changes) {
    if (t < change.t_s) break;
    if (change.ramp_s <= 0.0 || t >= change.t_s + change.ramp_s) {
      ps = change.ps;
    } else {
      ps += (change.ps - ps) * (t - change.t_s) / change.ramp_s;
    }
  }
  return ps;
}

}  // namespace leakmon::sim
