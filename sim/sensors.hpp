// The sensor chain of MODEL.md ("Reference, sensors, sampling" and "Simulation conventions"):
// transducer lag (integrated with the plant), then offset, then white noise, then quantisation
// clamped to the transducer's range. Each stage can be switched off for tests.
#pragma once

#include <cstdint>

#include "sim/effects.hpp"
#include "sim/random.hpp"

namespace leakmon::sim {

struct SensorSettings {
  bool enabled = true;  // false: every measurement is the true value (offset effects still apply)
  bool pressure_quantisation = true;
  double pressure_full_scale = 20.7e6;  // Pa; the range is 0..full scale
  int pressure_bits = 12;               // LSB = full scale / 2^bits = 5.05 kPa
  double pressure_noise_sigma = 5e3;    // Pa
  bool position_quantisation = true;
  double position_resolution = 10e-6;  // m
  double position_noise_sigma = 5e-6;  // m

  double pressure_lsb() const;
};

struct Measurement {
  double x, p1, p2;
};

// Turns true values into what the transducers report, drawing noise from its own stream.
class Sensors {
 public:
  Sensors(const SensorSettings& settings, const Effects& effects, std::uint64_t seed);
  void reset();
  // p1_transducer, p2_transducer: the pressures after any transducer lag (plant states).
  Measurement measure(double x, double p1_transducer, double p2_transducer) noexcept;

 private:
  double pressure(double p, double offset) noexcept;

  SensorSettings settings_;
  double offset_p1_ = 0.0, offset_p2_ = 0.0;
  std::uint64_t seed_;
  Random random_;
};

}  // namespace leakmon::sim
