#include "sim/reference.hpp"

namespace leakmon::sim {

Reference::Reference(const ReferenceSettings& settings, std::uint64_t seed)
    : settings_(settings), seed_(seed), random_(seed) {
  reset();
}

void Reference::reset() {
  random_.reseed(seed_);
  level_ = 0.0;
  level_end_ = 0.0;
}

void Reference::draw_level() noexcept {
  const double sign = random_.uniform() < 0.5 ? -1.0 : 1.0;
  const double amplitude = random_.uniform(settings_.amp_min, settings_.amp_max);
  const double hold = random_.uniform(settings_.hold_min, settings_.hold_max);
  level_ = sign * amplitude;
  level_end_ += hold;
}

void Reference::start_at(double t0) noexcept {
  level_ = 0.0;
  level_end_ = t0;
}

double Reference::at(double t) noexcept {
  while (t >= level_end_) draw_level();
  return level_;
}

}  // namespace leakmon::sim
