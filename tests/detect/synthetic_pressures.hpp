// Synthetic chamber pressure samples for the detectors that compute their own features
// (Observation::p1_samples): a lightly damped 75 Hz mode driven by white noise that moves the
// two chambers in antiphase (the hydraulic mode of MODEL.md's rig), plus independent transducer
// noise per chamber, on top of load pressures that step between holds. A leak damps the mode:
// its damping grows (pole radius falls) from `onset` on, so less of the band is antiphase.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include "detect/detector.hpp"

namespace leakmon::test {

struct SyntheticPressures {
  static constexpr int kHop = 20;  // samples per hop at 500 Hz: 0.04 s
  double rate = 500.0;
  double mode_hz = 75.0;
  double pole_radius = 0.97;       // healthy damping of the mode
  double leak_pole_radius = 0.97;  // from `onset` on
  double onset = 1e300;
  double mode_drive = 6e3;       // [Pa] per sample
  double sensor_noise = 5e3;     // [Pa], independent per chamber
  double supply = 17.2e6;        // p1 + p2 at rest (+ tank, ignored)
  double supply_after = 17.2e6;  // from `supply_step_at` on
  double supply_step_at = 1e300;
  std::mt19937_64 random{7};
  double t = 0.0;
  double mode[2] = {0.0, 0.0};
  double load = 0.0, hold_left = 0.0;
  std::array<double, kHop> p1{}, p2{};

  // One hop: the samples (spans into this object, valid until the next call) and their means.
  detect::Observation next() {
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    if ((hold_left -= kHop / rate) <= 0.0) {
      hold_left = 0.5 + 3.5 * uniform(random);
      load = (uniform(random) - 0.5) * 4e6;
    }
    const double radius = t >= onset ? leak_pole_radius : pole_radius;
    const double a1 = 2.0 * radius * std::cos(2.0 * std::numbers::pi * mode_hz / rate);
    const double a2 = -radius * radius;
    const double ps = t >= supply_step_at ? supply_after : supply;
    double sum1 = 0.0, sum2 = 0.0;
    for (int i = 0; i < kHop; ++i) {
      const double m = a1 * mode[0] + a2 * mode[1] + mode_drive * normal(random);
      mode[1] = mode[0];
      mode[0] = m;
      p1[i] = 0.5 * (ps + load) + m + sensor_noise * normal(random);
      p2[i] = 0.5 * (ps - load) - m + sensor_noise * normal(random);
      sum1 += p1[i];
      sum2 += p2[i];
    }
    t += kHop / rate;
    detect::Observation o;
    o.t = t;
    o.p1 = sum1 / kHop;
    o.p2 = sum2 / kHop;
    o.index_p1 = o.index_p2 = 3e4;
    o.p1_samples = p1;
    o.p2_samples = p2;
    return o;
  }
};

}  // namespace leakmon::test
