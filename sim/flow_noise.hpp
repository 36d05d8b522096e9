// Spool flow noise w of MODEL.md: an Ornstein-Uhlenbeck process (std. dev. sigma_w,
// correlation time tau_w) on the effective spool opening. Drawn by the exact discretisation
// w[n+1] = a w[n] + sigma sqrt(1 - a^2) N(0,1), a = exp(-dt/tau_w), on a fixed time grid and
// interpolated linearly in between: the values depend only on the seed and the grid, never on
// the integration step that samples them.
#pragma once

#include <cstdint>

#include "sim/random.hpp"

namespace leakmon::sim {

inline constexpr double kNoiseGridStep = 0.25e-3;  // s: 8 points per 2 ms sample

class FlowNoise {
 public:
  FlowNoise(double sigma, double tau, double grid_step_s, std::uint64_t seed);
  void reset();
  // w(t); t must not fall behind the grid cell of the previous call (until reset()).
  double at(double t) noexcept;
  // w(t) without drawing: exact within the current grid cell, held beyond it.
  double peek(double t) const noexcept;
  double grid_step() const { return grid_step_; }

 private:
  void draw_next() noexcept;

  double sigma_, grid_step_, decay_, innovation_;  // tau enters through decay_
  std::uint64_t seed_;
  Random random_;
  std::int64_t cell_ = 0;  // w_lo_ is w at cell_ * grid_step_, w_hi_ at the next grid point
  double w_lo_ = 0.0, w_hi_ = 0.0;
};

}  // namespace leakmon::sim
