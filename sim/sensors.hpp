// The sensor chain of MODEL.md ("Reference, sensors, sampling" and "Simulation conventions"):
// transducer lag (integrated with the plant), then offset, then white noise, then quantisation
// clamped to the transducer's range. Each stage can be switched off for tests.
#pragma once

#include <cstdint>

#include "sim/effects.hpp"
#include "sim/parameters.hpp"
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
  // Oil temperature (capture column temp): a Pt100 RTD with a 4-20 mA transmitter ranged
  // -50..150 degC, read to 0.1 K with 0.05 K of noise.
  double temp_resolution = 0.1;    // K
  double temp_noise_sigma = 0.05;  // K
  double temp_min = -50.0;         // degC
  double temp_max = 150.0;         // degC

  double pressure_lsb() const;
};

// MODEL.md's transducer chain ranged for the supply: the smallest of the usual ranges (10, 20.7,
// 25, 35, 40, 60 MPa) that reads 1.15 x the supply; the paper's 20.7 MPa on the paper's rig.
SensorSettings sensors_for(const Parameters& params);

// The quantisers of the chain (also used to re-quantise a spiked reading).
double quantise_pressure(const SensorSettings& s, double p) noexcept;  // clamped to the range
double quantise_position(const SensorSettings& s, double x) noexcept;
double quantise_temperature(const SensorSettings& s, double T) noexcept;  // clamped too

struct Measurement {
  double x, p1, p2;
};

// Turns true values into what the transducers report, drawing noise from its own stream.
class Sensors {
 public:
  Sensors(const SensorSettings& settings, const Effects& effects, std::uint64_t seed);
  void reset();
  // The transducer offsets of `effects` from now on (Scenario::change).
  void set_effects(const Effects& effects) noexcept;
  // p1_transducer, p2_transducer: the pressures after any transducer lag (plant states).
  Measurement measure(double x, double p1_transducer, double p2_transducer) noexcept;
  // The optional transducers (supply pressure: the pressure chain; oil temperature: the RTD),
  // with noise from a stream of their own, so that the p1, p2, x readings stay as without them.
  double supply_pressure(double ps) noexcept;
  double temperature(double T) noexcept;

 private:
  double pressure(double p, double offset) noexcept;

  SensorSettings settings_;
  double offset_p1_ = 0.0, offset_p2_ = 0.0;
  std::uint64_t seed_;
  Random random_;
  Random aux_random_;
};

}  // namespace leakmon::sim
