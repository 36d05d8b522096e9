#include "sim/flow_noise.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::sim {

FlowNoise::FlowNoise(double sigma, double tau, double grid_step_s, std::uint64_t seed)
    : sigma_(sigma),
      grid_step_(grid_step_s),
      decay_(std::exp(-grid_step_s / tau)),
      innovation_(sigma * std::sqrt(1.0 - decay_ * decay_)),
      seed_(seed),
      random_(seed) {
  reset();
}

void FlowNoise::reset() {
  random_.reseed(seed_);
  cell_ = 0;
  // Started from the stationary distribution: the valve was noisy before the run began.
  w_hi_ = sigma_ * random_.normal();
  w_lo_ = w_hi_;
  draw_next();
  cell_ = 0;
}

void FlowNoise::draw_next() noexcept {
  w_lo_ = w_hi_;
  w_hi_ = decay_ * w_hi_ + innovation_ * random_.normal();
  ++cell_;
}

double FlowNoise::at(double t) noexcept {
  const auto cell = static_cast<std::int64_t>(std::floor(t / grid_step_));
  while (cell_ < cell) draw_next();
  return peek(t);
}

double FlowNoise::peek(double t) const noexcept {
  // Linear interpolation keeps w continuous, so a grid point that rounding places a hair
  // before or after a step boundary changes nothing.
  const double fraction = std::min(t / grid_step_ - static_cast<double>(cell_), 1.0);
  return w_lo_ + (w_hi_ - w_lo_) * fraction;
}

}  // namespace leakmon::sim
