// Supply pressure (effect library "supply_ripple", "supply_droop"): ripple adds
// dP sin(2 pi f t) to ps0 first; droop ps = ps_r - R_s q_s(ps) is an algebraic loop because
// the supply land's flow depends on the drooped pressure, so it is solved, not lagged.
#pragma once

#include <cmath>

namespace leakmon::sim {

// supply_ripple: ps0 + dP sin(omega t). The cos term (dQ) lets the model check fit the line's
// phase; the simulator leaves it at 0.
inline double rippled_supply(double ps0, double dP, double dQ, double omega, double t) noexcept {
  if (dP == 0.0 && dQ == 0.0) return ps0;
  const double phase = omega * t;
  double ps = ps0 + dP * std::sin(phase);
  if (dQ != 0.0) ps += dQ * std::cos(phase);
  return ps;
}

struct SupplyInputs {
  double opening;  // effective spool opening o
  double p1, p2, pt;
  double Kv, dp_lin, C_n;
};

// q_s(ps): flow out of the supply port; strictly increasing in ps.
double supply_flow(double ps, const SupplyInputs& in) noexcept;

// Solves ps + R_s q_s(ps) = ps_undrooped (unique root: the left side is strictly increasing)
// by Newton's method safeguarded with bisection, to 1e-9 Pa relative. Allocation-free.
double drooped_supply(double ps_undrooped, double R_s, const SupplyInputs& in) noexcept;

}  // namespace leakmon::sim
