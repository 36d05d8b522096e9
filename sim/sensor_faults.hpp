// Sensor faults (MODEL.md "Sensor faults"), injected into the acquisition chain that records
// the capture, after quantisation: a frozen channel repeats the exact quantised value it last
// reported. The servo controller keeps its own healthy position feedback (a fault in the
// monitoring DAQ does not move the actuator), so every fault lives in its channel only.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "sim/random.hpp"
#include "sim/sensors.hpp"

namespace leakmon::sim {

enum class SensorChannel { p1, p2, x, ps, temp };
std::string_view to_string(SensorChannel channel);

struct SensorFault {
  enum class Kind { frozen, saturated, spikes, dropout };
  Kind kind = Kind::frozen;
  SensorChannel channel = SensorChannel::p1;
  double start_s = 0.0;
  double duration_s = std::numeric_limits<double>::infinity();
  // saturated: the top of the range (pressures 20.7 MPa, x +L/2, temp 150 degC) or its bottom
  // (0 Pa, -L/2, -50 degC).
  bool high = true;
  // spikes: isolated samples off by +-magnitude (random sign; the channel's unit: Pa, m, K),
  // each sample independently with probability rate_per_min / (60 fs), so the count per minute
  // is Poisson; re-quantised and clamped to the range like any reading.
  double rate_per_min = 4.0;
  double magnitude = 3e6;
  // dropout: reads 0 (false) or is missing, NaN = an empty field in the capture (true).
  bool gap = false;

  bool active(double t) const noexcept { return t >= start_s && t < start_s + duration_s; }
  std::string describe() const;
};
std::string_view to_string(SensorFault::Kind kind);

// The recorded channels of one sample.
struct Readings {
  double p1, p2, x, ps, temp;
  double& operator[](SensorChannel channel) noexcept;
};

class SensorFaults {
 public:
  // x_range: the position transducer's range +-x_range (half the stroke).
  SensorFaults(std::vector<SensorFault> faults, const SensorSettings& settings, double x_range,
               std::uint64_t seed);
  void reset();
  // Applies every fault active at t (in list order) to r, and remembers what was reported.
  // Allocation-free.
  void apply(double t, double sample_period, Readings& r) noexcept;
  const std::vector<SensorFault>& faults() const { return faults_; }

 private:
  struct State {
    Random random;
    bool holding = false;
    double held = 0.0;
  };
  double requantise(SensorChannel channel, double value) const noexcept;
  double range_end(SensorChannel channel, bool high) const noexcept;

  std::vector<SensorFault> faults_;
  std::vector<State> states_;
  SensorSettings settings_;
  double x_range_;
  std::uint64_t seed_;
  Readings last_{};
  bool has_last_ = false;
};

}  // namespace leakmon::sim
