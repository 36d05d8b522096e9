// The paper's pseudorandom step reference (MODEL.md "Reference"): each level is s * a with
// s = +-1 at random and a uniform in [amp_min, amp_max], held for a duration uniform in
// [hold_min, hold_max]; the first level starts at t = 0. Seeded and reproducible.
#pragma once

#include <cstdint>

#include "sim/random.hpp"

namespace leakmon::sim {

struct ReferenceSettings {
  double amp_min = 0.025, amp_max = 0.05;  // m
  double hold_min = 0.5, hold_max = 4.0;   // s
};

class Reference {
 public:
  Reference(const ReferenceSettings& settings, std::uint64_t seed);
  void reset();
  // The level at time t; t must not decrease between calls (until reset()).
  double at(double t) noexcept;
  // Starts a new level at t0 (a program's steps phase), drawing on from the same stream.
  void start_at(double t0) noexcept;

 private:
  void draw_level() noexcept;

  ReferenceSettings settings_;
  std::uint64_t seed_;
  Random random_;
  double level_ = 0.0;
  double level_end_ = 0.0;
};

}  // namespace leakmon::sim
