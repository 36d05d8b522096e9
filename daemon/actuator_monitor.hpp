// One actuator's path from samples to alarm events: streaming wavelet index of p1 (and p2),
// the hop summary the detector needs (detect::Observation), the detector, and the alarm state
// machine. Runs on the worker thread; allocates only when built.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "daemon/alarm.hpp"
#include "daemon/config.hpp"
#include "daemon/event.hpp"
#include "daemon/sample.hpp"
#include "daemon/state_store.hpp"
#include "detect/detector.hpp"
#include "dsp/streaming_features.hpp"

namespace leakmon::daemon {

// Where each role's value sits in a group's Sample; -1 when the actuator does not acquire it.
struct ChannelLayout {
  int p1 = -1, p2 = -1, u = -1, x = -1, xref = -1;
};

// What the metrics and `leakmon status` show for one actuator.
struct ActuatorStatus {
  std::string name;
  std::string alarm;
  std::string detector;
  AlarmState state = AlarmState::normal;
  bool learning = true;
  double t = kNoValue;         // source time of the newest decision
  double index_p1 = kNoValue;  // Pa
  double index_p2 = kNoValue;
  double score = kNoValue;
  double baseline = kNoValue;
  double leak_coefficient = kNoValue;
  std::uint64_t decisions = 0;
  std::uint64_t gap_samples = 0;  // samples that arrived as gaps (missed ticks, NaN reads)
};

using EventPublisher = std::function<void(const Event&)>;

class ActuatorMonitor {
 public:
  ActuatorMonitor(const ActuatorConfig& config, const ChannelLayout& layout,
                  std::int64_t period_ns);

  const std::string& name() const { return config_.name; }
  const ActuatorConfig& config() const { return config_; }
  const ChannelLayout& layout() const { return layout_; }

  // One sample of the actuator's group. Returns true when it completed a hop (a decision).
  bool push(const Sample& sample, const EventPublisher& publish);
  // A sample that never arrived (missed cycle or ring drop) at source time t: a gap.
  void push_gap(double t, const EventPublisher& publish);

  void acknowledge(const EventPublisher& publish);
  // Adopt new alarm settings (reload) without losing state.
  void set_alarm_settings(const AlarmSettings& settings);
  // True when `other` can take over this monitor's learned state (same signals and features).
  bool same_pipeline(const ActuatorConfig& other, const ChannelLayout& other_layout) const;

  ActuatorStatus status() const;

  // Persistence across restarts (state_store.hpp). Not for the real-time path: both allocate.
  const StateFingerprint& fingerprint() const { return fingerprint_; }
  ActuatorState export_state() const;
  // Resumes from a saved state of the same fingerprint: the detector's learning and test, and
  // the annunciated alarm. The time the daemon was down counts as one gap in the data (the
  // detector sees one hop without values), so nothing is spliced across it. Throws
  // detect::StateError when the detector cannot take the state; it then learns afresh.
  void import_state(const ActuatorState& state);

 private:
  void decide(double t, const EventPublisher& publish);
  Event alarm_event(EventKind kind, double t) const;
  AlarmSettings effective(const AlarmSettings& configured) const;

  ActuatorConfig config_;
  ChannelLayout layout_;
  dsp::StreamingFeatures features_;
  std::unique_ptr<detect::Detector> detector_;
  Alarm alarm_;
  StateFingerprint fingerprint_;

  // Hop accumulators: sums and counts of u, x, p1, p2 over the newest `step` samples.
  struct HopMean {
    double sum = 0.0;
    bool gap = false;
    void add(double v) {
      if (std::isnan(v)) gap = true;
      sum += v;
    }
  };
  HopMean hop_u_, hop_x_, hop_p1_, hop_p2_;
  std::size_t hop_samples_ = 0;
  // Ring of the excitation signal (xref, else x) over the window, for Observation::x_activity.
  std::vector<double> activity_;
  std::size_t activity_next_ = 0;
  std::size_t activity_filled_ = 0;
  std::vector<double> index_input_;  // scratch: the index channels of one sample

  detect::Decision last_decision_;
  double last_t_ = kNoValue;
  double last_load_pressure_ = kNoValue;
  std::uint64_t decisions_ = 0;
  std::uint64_t gap_samples_ = 0;
};

}  // namespace leakmon::daemon
