// Small helpers shared by the simulator tests: run a scenario into memory, hold one reference
// level, summarise a stretch of samples.
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

#include "sim/rig.hpp"
#include "sim/scenario.hpp"

namespace leakmon::sim::testing {

inline std::vector<RigSample> run(const Scenario& scenario) {
  Rig rig(scenario);
  std::vector<RigSample> out(scenario.samples());
  for (auto& sample : out) sample = rig.step();
  return out;
}

// A scenario whose reference holds one level of magnitude `amplitude` for the whole run (its
// sign still comes from the seed), with noise-free flow and ideal sensors unless re-enabled.
inline Scenario held_level(double amplitude, double duration_s, ControllerKind controller,
                           std::uint64_t seed = 1) {
  Scenario s;
  s.name = "held-level";
  s.controller = controller;
  s.duration_s = duration_s;
  s.seed = seed;
  s.reference = {amplitude, amplitude, duration_s + 1.0, duration_s + 1.0};
  s.params.sigma_w = 0.0;
  s.sensors.enabled = false;
  return s;
}

// Mean of `field` over samples with t in [t0, t1).
inline double mean_over(const std::vector<RigSample>& run, double t0, double t1,
                        const std::function<double(const RigSample&)>& field) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& s : run) {
    if (s.t < t0 || s.t >= t1) continue;
    sum += field(s);
    ++n;
  }
  return n ? sum / static_cast<double>(n) : std::nan("");
}

}  // namespace leakmon::sim::testing
