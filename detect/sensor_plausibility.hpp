// Per-channel plausibility of one transducer's stream (MODEL.md "Sensor faults"): frozen,
// saturated at a range end, spiking, dropped out. Every threshold derives from the transducer's
// configured range, resolution and noise (TransducerSpec), none is tuned to a capture; the
// derivations are in sensor_plausibility.cpp and docs/detection.md ("Sensor faults").
//
// It also cleans the stream: an isolated spike (Hampel test against the median of its two
// neighbours on either side) is replaced by that median, so the stream that leaves push() is
// the input delayed by kDelay samples. Allocation-free after construction.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string_view>

#include "io/device_status.hpp"

namespace leakmon::detect {

// What the transducer is, as configured (defaults: MODEL.md's pressure transducers).
struct TransducerSpec {
  bool enabled = true;
  double min = 0.0;  // range ends in the channel's unit; +-inf: no range end to saturate at
  double max = 20.7e6;
  double resolution = 20.7e6 / 4096.0;  // one LSB (12 bit over the range); 0: unquantised
  double noise_sigma = 5e3;             // white noise at rest, in the channel's unit

  static TransducerSpec pressure() { return {}; }
  // MODEL.md's position transducer: 10 um resolution, 5 um noise, no range end configured.
  static TransducerSpec position() {
    return {true, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            10e-6, 5e-6};
  }
};

enum class SensorFault : std::uint8_t { none, frozen, saturated, spikes, dropout };

std::string_view to_string(SensorFault fault);

// NAMUR NE 107 category of a fault: frozen/dropout -> failure (the output is invalid),
// saturated/spikes -> out_of_specification.
io::DeviceStatus device_status(SensorFault fault);

// Sample counts derived from a spec at a sample rate (exposed for tests and documentation).
struct PlausibilityLimits {
  std::uint32_t frozen_run = 0;   // exact repeats that make "frozen" (0: check off)
  std::uint32_t suspect_run = 0;  // exact repeats after which the stream is not trusted
  std::uint32_t saturated_run = 0;
  std::uint32_t dropout_run = 0;
  std::uint32_t spike_quiet = 0;  // "spikes" from a rejected spike until this many quiet samples
  std::uint32_t recovery = 0;     // fault-free samples before the status returns to ok
  double spike_sigma = 0.0;       // Hampel threshold floor [channel unit]
  double deviation_noise = 0.0;   // mean |sample - neighbours' median| of the noise alone
  double deviation_memory = 0.0;  // weight of each sample in the channel's deviation scale
  std::uint32_t deviation_warmup = 0;  // samples before a rejected sample is named a spike
  bool zero_is_dropout = false;        // 0 is the bottom of the range: exact zeros mean no signal
};

PlausibilityLimits plausibility_limits(const TransducerSpec& spec, double sample_rate_hz);

class SensorPlausibility {
 public:
  static constexpr std::size_t kDelay = 2;  // samples between a value's arrival and its release

  SensorPlausibility(const TransducerSpec& spec, double sample_rate_hz);

  // New settings (a configuration reload): the limits follow, the stream's history and runs stay.
  void reconfigure(const TransducerSpec& spec, double sample_rate_hz);

  // One raw sample (NaN = missing). Returns the cleaned sample of kDelay samples ago (NaN
  // before kDelay samples have arrived).
  double push(double value) noexcept;

  // The fault reported now: active, or recovering (condition gone, recovery not yet over).
  SensorFault fault() const { return reported_; }
  bool recovering() const { return reported_ != SensorFault::none && active_ == SensorFault::none; }
  // ok; failure / out_of_specification while a fault is active; maintenance_required while
  // recovering (the output is valid again, but the channel has just been faulty).
  io::DeviceStatus status() const;
  // True while a fault other than spikes is reported or a condition is building up (a run of
  // repeats, values at a range end, gaps): the stream must not teach or drive a detector then.
  // Spikes are replaced sample by sample, so they do not make the stream suspect.
  bool suspect() const;

  std::uint64_t spikes_rejected() const { return spikes_rejected_; }
  const PlausibilityLimits& limits() const { return limits_; }

 private:
  SensorFault condition() const;

  TransducerSpec spec_;
  PlausibilityLimits limits_;
  std::array<double, 2 * kDelay + 1> history_{};  // newest at (next_ - 1)
  std::size_t next_ = 0;
  std::uint64_t samples_ = 0;

  double last_value_ = std::numeric_limits<double>::quiet_NaN();
  std::uint32_t repeat_run_ = 0;      // samples in the current run of one exact value
  bool run_began_with_jump_ = false;  // that run's first value leapt off the stream before it
  std::uint32_t band_run_ = 0;        // consecutive samples within one LSB of a range end
  std::uint32_t zero_run_ = 0;        // consecutive exact zeros (when zero_is_dropout)
  std::uint32_t nan_run_ = 0;
  std::uint64_t last_spike_ = 0;  // sample number of the last rejected spike; 0: none
  // The channel's own mean deviation from its neighbours' median (rejected samples left out).
  double deviation_scale_ = 0.0;
  std::uint64_t spikes_rejected_ = 0;

  SensorFault active_ = SensorFault::none;
  SensorFault reported_ = SensorFault::none;
  std::uint32_t clean_run_ = 0;  // samples since the condition ended
};

}  // namespace leakmon::detect
