#include "sim/sensors.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::sim {

double SensorSettings::pressure_lsb() const {
  return pressure_full_scale / std::ldexp(1.0, pressure_bits);
}

Sensors::Sensors(const SensorSettings& settings, const Effects& effects, std::uint64_t seed)
    : settings_(settings), seed_(seed), random_(seed) {
  if (effects.sensor_offset) {
    (effects.sensor_offset->channel == PressureChannel::p1 ? offset_p1_ : offset_p2_) =
        effects.sensor_offset->offset;
  }
}

void Sensors::reset() { random_.reseed(seed_); }

double Sensors::pressure(double p, double offset) noexcept {
  // Always drawn, so that switching a stage off leaves the other channels' noise unchanged.
  const double noise = random_.normal();
  double reading = p + offset;
  if (!settings_.enabled) return reading;
  reading += settings_.pressure_noise_sigma * noise;
  if (settings_.pressure_quantisation) {
    const double lsb = settings_.pressure_lsb();
    const double top_code = std::ldexp(1.0, settings_.pressure_bits) - 1.0;
    reading = std::clamp(std::nearbyint(reading / lsb), 0.0, top_code) * lsb;
  }
  return reading;
}

Measurement Sensors::measure(double x, double p1_transducer, double p2_transducer) noexcept {
  Measurement m{};
  m.p1 = pressure(p1_transducer, offset_p1_);
  m.p2 = pressure(p2_transducer, offset_p2_);
  const double noise = random_.normal();
  m.x = x;
  if (settings_.enabled) {
    m.x += settings_.position_noise_sigma * noise;
    if (settings_.position_quantisation) {
      // + 0.0 turns a rounded -0 into 0, so captures do not print "-0".
      m.x =
          std::nearbyint(m.x / settings_.position_resolution) * settings_.position_resolution + 0.0;
    }
  }
  return m;
}

}  // namespace leakmon::sim
