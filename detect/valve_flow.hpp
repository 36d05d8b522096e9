// The servovalve's orifice law (MODEL.md "valve", sim/valve.hpp), used to turn a command and
// the chamber pressures into the flow the valve delivers, in units of the unknown valve
// coefficient Kv.
#pragma once

#include "sim/parameters.hpp"
#include "sim/spool.hpp"
#include "sim/valve.hpp"

namespace leakmon::detect {

// Load flow (q1 - q2) / 2 divided by Kv [sqrt(Pa)] at the steady-state opening sat(u / u_max),
// without the null leakage: the mean of what the valve sends into chamber 1 and takes out of
// chamber 2. Averaging the two chambers cancels most of the compressibility flow and anything
// that moves p1 + p2.
inline double load_flow_per_kv(const sim::Parameters& rig, double u, double p1, double p2) {
  const sim::ValveFlows f = sim::valve_flows(sim::spool_command(u, rig.u_max), rig.ps, rig.pt, p1,
                                             p2, 1.0, rig.dp_lin, 0.0);
  return 0.5 * (f.q1 - f.q2);
}

}  // namespace leakmon::detect
