#include "sim/supply.hpp"

#include <algorithm>
#include <cmath>

#include "sim/valve.hpp"

namespace leakmon::sim {
namespace {

// The chamber the supply land feeds: 1 for o >= 0, 2 otherwise (valve.hpp).
double fed_chamber_pressure(const SupplyInputs& in) { return in.opening >= 0.0 ? in.p1 : in.p2; }

}  // namespace

double supply_flow(double ps, const SupplyInputs& in) noexcept {
  return in.Kv * std::abs(in.opening) * orifice(ps - fed_chamber_pressure(in), in.dp_lin) +
         in.C_n * ((ps - in.p1) + (ps - in.p2));
}

double drooped_supply(double ps_undrooped, double R_s, const SupplyInputs& in) noexcept {
  if (R_s <= 0.0) return ps_undrooped;
  const auto residual = [&](double ps) { return ps + R_s * supply_flow(ps, in) - ps_undrooped; };
  // residual(lo) <= 0 <= residual(hi): below both chamber pressures no flow leaves the supply.
  double lo = std::min({ps_undrooped, in.p1, in.p2});
  double hi = std::max({ps_undrooped, in.p1, in.p2});
  double ps = ps_undrooped;
  const double p_fed = fed_chamber_pressure(in);
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double r = residual(ps);
    if (r > 0.0) {
      hi = ps;
    } else {
      lo = ps;
    }
    const double slope =
        1.0 +
        R_s * (in.Kv * std::abs(in.opening) * orifice_slope(ps - p_fed, in.dp_lin) + 2.0 * in.C_n);
    double next = ps - r / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool converged = std::abs(next - ps) <= 1e-9 * std::max(std::abs(ps), 1.0);
    ps = next;
    if (converged || hi - lo <= 1e-9 * std::max(std::abs(hi), 1.0)) break;
  }
  return ps;
}

}  // namespace leakmon::sim
