// The piston's force balance (MODEL.md): m dv/dt = A (p1 - p2) - b v - K_s x - F_fric(v).
// Everything in it but m, b and the friction is measured or known (the load spring K_s is
// the rig's stated one, or an unknown too for the rig check), so integrated over short
// windows it is a linear regression:
//   m (v(t2) - v(t1)) + b (x(t2) - x(t1)) + F_C int tanh(v/1e-3) dt + c (t2 - t1)
//     = int (A (p1 - p2) - K_s x) dt
// It pins m down directly, where the simulation fit only sees the hydraulic mode, which beta,
// m and b set together (the calibration's beta/m/b valley). b is less certain here (over the
// moving windows v and the friction term's sign(v) are alike), so it is only a starting point. The
// friction and constant terms keep Coulomb friction and a pressure transducer's offset from biasing
// m and b; the window's pressure changes p_i(t2) - p_i(t1) absorb a transducer lag (a lag tau reads
// p - tau dp/dt, which integrates to tau (p(t2) - p(t1))).
#pragma once

#include <span>

#include "model/measured_record.hpp"
#include "model/segment_predictor.hpp"
#include "sim/parameters.hpp"

namespace leakmon::model {

struct ForceBalance {
  double m = 0.0;        // moving mass [kg]
  double b = 0.0;        // viscous friction [N s/m]
  double m_error = 0.0;  // standard errors from the regression's residuals
  double b_error = 0.0;
  // A constant force in the balance [N] (c above): a pressure transducer's offset o reads as
  // A o on the load pressure.
  double constant = 0.0, constant_error = 0.0;
  // The load spring when it is an unknown too (free_stiffness), else the rig's [N/m].
  double K_s = 0.0, K_s_error = 0.0;
  std::size_t windows = 0;
};

// Enough windows and m within twice MODEL.md's calibratable range around the stated mass
// (the fit's bounds), known to 10 %: anything else means the capture hardly moves the piston
// or the balance does not hold.
bool usable(const ForceBalance& estimate, double stated_m = sim::Parameters{}.m);

// Regression over windows of `window_samples` inside the given segments. With
// `free_stiffness` the load spring K_s is an unknown of the regression (the rig check's load
// stiffness, given the area), else the rig's.
ForceBalance estimate_force_balance(const MeasuredRecord& record, std::span<const Segment> segments,
                                    const sim::Parameters& rig = sim::Parameters::nominal(),
                                    std::size_t window_samples = 25, bool free_stiffness = false);

}  // namespace leakmon::model
