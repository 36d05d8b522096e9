#include "sim/oil.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <utility>

namespace leakmon::sim {
namespace {

constexpr double kKelvin = 273.15;
constexpr double kWaltherShift = 0.7;  // mm^2/s, ASTM D341

double walther_w(double nu) { return std::log10(std::log10(nu + kWaltherShift)); }

}  // namespace

Oil::Oil(double nu40, double nu100, std::string name)
    : nu40_(nu40), nu100_(nu100), name_(std::move(name)) {
  // Walther's law needs log10(nu + 0.7) > 0, i.e. nu > 0.3 mm^2/s.
  if (!(nu100 > 0.3 && nu40 > nu100 && std::isfinite(nu40))) {
    throw std::invalid_argument(fmt::format(
        "oil viscosities must satisfy nu40 > nu100 > 0.3 mm^2/s (got nu40 = {:g}, nu100 = {:g})",
        nu40, nu100));
  }
  const double x40 = std::log10(kReferenceTemperature + kKelvin);
  const double x100 = std::log10(100.0 + kKelvin);
  B_ = (walther_w(nu40) - walther_w(nu100)) / (x100 - x40);
  A_ = walther_w(nu40) + B_ * x40;
  nu_reference_ = nu(kReferenceTemperature);
}

std::optional<Oil> Oil::iso_vg(int grade) {
  // MODEL.md's table (typical data-sheet values of mineral hydraulic oils, VI about 100).
  switch (grade) {
    case 32:
      return Oil(32.0, 5.4, "ISO VG 32");
    case 46:
      return Oil(46.0, 6.8, "ISO VG 46");
    case 68:
      return Oil(68.0, 8.7, "ISO VG 68");
    default:
      return std::nullopt;
  }
}

double Oil::nu(double T) const noexcept {
  const double w = A_ - B_ * std::log10(T + kKelvin);
  return std::pow(10.0, std::pow(10.0, w)) - kWaltherShift;
}

double Oil::ratio(double T) const noexcept { return nu_reference_ / nu(T); }

double Oil::viscosity_slope(double T) const noexcept {
  // nu + 0.7 = 10^(10^w), w = A - B log10(T_K):
  // d ln(nu)/dT = (nu + 0.7)/nu * ln(10) * 10^w * ln(10) * dw/dT, dw/dT = -B / (T_K ln 10).
  const double T_K = T + kKelvin;
  const double w = A_ - B_ * std::log10(T_K);
  const double n = nu(T);
  return (n + kWaltherShift) / n * std::log(10.0) * std::pow(10.0, w) * B_ / T_K;
}

}  // namespace leakmon::sim
