#include "sim/sensors.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::sim {

SensorSettings sensors_for(const Parameters& p) {
  SensorSettings sensors;
  for (const double range : {10e6, 20.7e6, 25e6, 35e6, 40e6, 60e6}) {
    sensors.pressure_full_scale = range;
    if (range >= 1.15 * p.ps) break;
  }
  return sensors;
}

double SensorSettings::pressure_lsb() const {
  return pressure_full_scale / std::ldexp(1.0, pressure_bits);
}

double quantise_pressure(const SensorSettings& s, double p) noexcept {
  const double lsb = s.pressure_lsb();
  const double top_code = std::ldexp(1.0, s.pressure_bits) - 1.0;
  return std::clamp(std::nearbyint(p / lsb), 0.0, top_code) * lsb;
}

double quantise_position(const SensorSettings& s, double x) noexcept {
  // + 0.0 turns a rounded -0 into 0, so captures do not print "-0".
  return std::nearbyint(x / s.position_resolution) * s.position_resolution + 0.0;
}

double quantise_temperature(const SensorSettings& s, double T) noexcept {
  // Dividing by the (exact, for 0.1 K) number of steps per kelvin keeps 40.1 printing as 40.1.
  const double steps_per_kelvin = 1.0 / s.temp_resolution;
  return std::clamp(std::nearbyint(T * steps_per_kelvin) / steps_per_kelvin + 0.0, s.temp_min,
                    s.temp_max);
}

namespace {
// Stream of the optional transducers, derived from the sensor seed.
constexpr std::uint64_t kAuxiliaryStream = 7;
}  // namespace

Sensors::Sensors(const SensorSettings& settings, const Effects& effects, std::uint64_t seed)
    : settings_(settings),
      seed_(seed),
      random_(seed),
      aux_random_(stream_seed(seed, kAuxiliaryStream)) {
  set_effects(effects);
}

void Sensors::set_effects(const Effects& effects) noexcept {
  offset_p1_ = offset_p2_ = 0.0;
  if (effects.sensor_offset) {
    (effects.sensor_offset->channel == PressureChannel::p1 ? offset_p1_ : offset_p2_) =
        effects.sensor_offset->offset;
  }
}

void Sensors::reset() {
  random_.reseed(seed_);
  aux_random_.reseed(stream_seed(seed_, kAuxiliaryStream));
}

double Sensors::supply_pressure(double ps) noexcept {
  const double noise = aux_random_.normal();
  if (!settings_.enabled) return ps;
  const double reading = ps + settings_.pressure_noise_sigma * noise;
  return settings_.pressure_quantisation ? quantise_pressure(settings_, reading) : reading;
}

double Sensors::temperature(double T) noexcept {
  const double noise = aux_random_.normal();
  if (!settings_.enabled) return T;
  return quantise_temperature(settings_, T + settings_.temp_noise_sigma * noise);
}

double Sensors::pressure(double p, double offset) noexcept {
  // Always drawn, so that switching a stage off leaves the other channels' noise unchanged.
  const double noise = random_.normal();
  double reading = p + offset;
  if (!settings_.enabled) return reading;
  reading += settings_.pressure_noise_sigma * noise;
  if (settings_.pressure_quantisation) reading = quantise_pressure(settings_, reading);
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
    if (settings_.position_quantisation) m.x = quantise_position(settings_, m.x);
  }
  return m;
}

}  // namespace leakmon::sim
