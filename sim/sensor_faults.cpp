#include "sim/sensor_faults.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace leakmon::sim {

std::string_view to_string(SensorChannel channel) {
  switch (channel) {
    case SensorChannel::p1:
      return "p1";
    case SensorChannel::p2:
      return "p2";
    case SensorChannel::x:
      return "x";
    case SensorChannel::ps:
      return "ps";
    case SensorChannel::temp:
      return "temp";
  }
  return "p1";
}

std::string_view to_string(SensorFault::Kind kind) {
  switch (kind) {
    case SensorFault::Kind::frozen:
      return "frozen";
    case SensorFault::Kind::saturated:
      return "saturated";
    case SensorFault::Kind::spikes:
      return "spikes";
    case SensorFault::Kind::dropout:
      return "dropout";
  }
  return "frozen";
}

std::string SensorFault::describe() const {
  std::string out = fmt::format("{} channel={} start_s={:g} duration_s={:g}", to_string(kind),
                                to_string(channel), start_s, duration_s);
  switch (kind) {
    case Kind::saturated:
      out += high ? " level=high" : " level=low";
      break;
    case Kind::spikes:
      out += fmt::format(" rate_per_min={:g} magnitude={:g}", rate_per_min, magnitude);
      break;
    case Kind::dropout:
      out += gap ? " mode=gap" : " mode=zero";
      break;
    case Kind::frozen:
      break;
  }
  return out;
}

double& Readings::operator[](SensorChannel channel) noexcept {
  switch (channel) {
    case SensorChannel::p1:
      return p1;
    case SensorChannel::p2:
      return p2;
    case SensorChannel::x:
      return x;
    case SensorChannel::ps:
      return ps;
    case SensorChannel::temp:
      return temp;
  }
  return p1;
}

SensorFaults::SensorFaults(std::vector<SensorFault> faults, const SensorSettings& settings,
                           double x_range, std::uint64_t seed)
    : faults_(std::move(faults)), settings_(settings), x_range_(x_range), seed_(seed) {
  states_.resize(faults_.size());
  reset();
}

void SensorFaults::reset() {
  // One stream per fault: adding a fault leaves the others' spikes where they were.
  for (std::size_t i = 0; i < states_.size(); ++i) {
    states_[i].holding = false;
    states_[i].held = 0.0;
    states_[i].random.reseed(stream_seed(seed_, i + 1));
  }
  has_last_ = false;
}

double SensorFaults::range_end(SensorChannel channel, bool high) const noexcept {
  switch (channel) {
    case SensorChannel::x:
      return high ? x_range_ : -x_range_;
    case SensorChannel::temp:
      return high ? settings_.temp_max : settings_.temp_min;
    case SensorChannel::p1:
    case SensorChannel::p2:
    case SensorChannel::ps:
      break;
  }
  return high ? settings_.pressure_full_scale : 0.0;
}

double SensorFaults::requantise(SensorChannel channel, double value) const noexcept {
  if (!settings_.enabled) return value;
  switch (channel) {
    case SensorChannel::x:
      return settings_.position_quantisation ? quantise_position(settings_, value) : value;
    case SensorChannel::temp:
      return quantise_temperature(settings_, value);
    case SensorChannel::p1:
    case SensorChannel::p2:
    case SensorChannel::ps:
      break;
  }
  return settings_.pressure_quantisation ? quantise_pressure(settings_, value)
                                         : std::clamp(value, 0.0, settings_.pressure_full_scale);
}

void SensorFaults::apply(double t, double sample_period, Readings& r) noexcept {
  for (std::size_t i = 0; i < faults_.size(); ++i) {
    const SensorFault& fault = faults_[i];
    State& state = states_[i];
    double& value = r[fault.channel];
    if (!fault.active(t)) {
      state.holding = false;
      continue;
    }
    switch (fault.kind) {
      case SensorFault::Kind::frozen:
        if (!state.holding) {
          // The DAQ holds the last value it delivered (or, from the first sample, that one).
          state.held = has_last_ ? last_[fault.channel] : value;
          state.holding = true;
        }
        value = state.held;
        break;
      case SensorFault::Kind::saturated:
        value = range_end(fault.channel, fault.high);
        break;
      case SensorFault::Kind::spikes: {
        const double p = fault.rate_per_min * sample_period / 60.0;
        const double u = state.random.uniform();
        const double sign = state.random.uniform() < 0.5 ? -1.0 : 1.0;
        if (u < p) value = requantise(fault.channel, value + sign * fault.magnitude);
        break;
      }
      case SensorFault::Kind::dropout:
        value = fault.gap ? std::nan("") : 0.0;
        break;
    }
  }
  last_ = r;
  has_last_ = true;
}

}  // namespace leakmon::sim
