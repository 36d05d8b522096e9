// One actuator's path from samples to alarm events: streaming wavelet index of p1 (and p2),
// the hop summary the detector needs (detect::Observation), the detector, and the alarm state
// machine. Runs on the worker thread; allocates only when built (and when it publishes an event).
//
// Before the index, every transducer channel (p1, p2, x) passes its plausibility check
// (detect::SensorPlausibility): isolated spikes are replaced by the median of their neighbours,
// so the whole pipeline runs SensorPlausibility::kDelay samples (4 ms at 500 Hz) behind the
// newest sample. A frozen, saturated, spiking or dropped-out channel raises a `sensor_fault`
// alarm naming it, and while any channel is faulty or suspect the detector is not fed (its score
// and learned state are held) until a full window of plausible data has passed again.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "capture/role.hpp"
#include "detect/detector.hpp"
#include "detect/sensor_plausibility.hpp"
#include "dsp/streaming_features.hpp"
#include "io/event.hpp"
#include "pipeline/alarm.hpp"
#include "pipeline/config.hpp"
#include "pipeline/mode_visibility.hpp"
#include "pipeline/repeated_samples.hpp"
#include "pipeline/state_store.hpp"
#include "realtime/sample.hpp"

namespace leakmon::pipeline {

// Where each role's value sits in a group's Sample; -1 when the actuator does not acquire it.
struct ChannelLayout {
  capture::ByRole<int> index{-1};

  int operator[](capture::Role role) const { return index[role]; }
  // The roles that have a place.
  capture::ByRole<bool> acquired() const;
  friend bool operator==(const ChannelLayout&, const ChannelLayout&) = default;
};

// One transducer channel's plausibility, for the metrics and `leakmon status`.
struct ChannelHealth {
  std::string channel;  // role: p1, p2, x
  io::DeviceStatus status = io::DeviceStatus::ok;
  detect::SensorFault fault = detect::SensorFault::none;  // also while recovering
  std::uint64_t spikes_rejected = 0;
};

// What the metrics and `leakmon status` show for one actuator.
struct ActuatorStatus {
  std::string name;
  std::string alarm;
  std::string detector;
  AlarmState state = AlarmState::normal;
  bool learning = true;
  // Source seconds until the detector decides: 0 once it does, NaN before the first sample.
  double learning_seconds_left = io::kNoValue;
  // How long learning takes from the first sample (the features' first window and the
  // detector's settling and learning), and the source time it ended (NaN: not yet, or resumed
  // from a learned state).
  double learning_seconds = io::kNoValue;
  double learning_ended_t = io::kNoValue;
  double raise_threshold = io::kNoValue;  // the score at which the alarm raises
  double clear_threshold = io::kNoValue;
  double t = io::kNoValue;         // source time of the newest decision
  double index_p1 = io::kNoValue;  // Pa
  double index_p2 = io::kNoValue;
  double score = io::kNoValue;
  double baseline = io::kNoValue;
  double leak_coefficient =
      io::kNoValue;  // m^3/(s Pa), at 40 degC when the oil temperature is known
  double leak_coefficient_ci = io::kNoValue;  // its 95 % half-width
  double oil_temperature = io::kNoValue;      // degC, newest hop mean of the `temp` channel
  double p1 = io::kNoValue;                   // Pa, chamber pressures: newest hop means
  double p2 = io::kNoValue;
  std::uint64_t decisions = 0;
  std::uint64_t gap_samples = 0;  // samples that arrived as gaps (missed ticks, NaN reads)
  // Samples among the last RepeatedSampleCheck::kWindow that repeat the one before exactly.
  std::uint64_t repeated_samples = 0;
  // Pressure-only detectors: the median index of the learning period over the transducer's noise
  // floor, best chamber (NaN before learning ends, or when the detector does not need the
  // hydraulic mode), and whether that makes the rig blind to a leak (ModeVisibilityCheck).
  double mode_visibility = io::kNoValue;
  bool detection_blind = false;
  std::vector<ChannelHealth> channels;
  bool suspended = false;                 // the detector is not fed: a channel is faulty or suspect
  std::uint64_t suspended_decisions = 0;  // hops not given to the detector for that reason
  std::uint64_t relearns = 0;             // how often a reload made the detector learn again
  // Whether the newest decision could have revealed a leak; why not; the source time it
  // stopped judging (NaN while judging); the source seconds of decisions (hops the detector
  // was given or held back from) and of those judged, since the monitor started.
  bool judged = false;
  detect::NotJudgedReason not_judged_reason = detect::NotJudgedReason::learning;
  double not_judged_since = io::kNoValue;
  double judged_seconds = 0.0;
  double decided_seconds = 0.0;
  // Wall time [s since 1970] the learned state kept in the state directory was saved; NaN when
  // none is. The service fills it: it is the one that saves (views/snapshot.hpp).
  double learned_state_saved_unix = io::kNoValue;
};

using EventPublisher = std::function<void(const io::Event&)>;

class ActuatorMonitor {
 public:
  ActuatorMonitor(const ActuatorConfig& config, const ChannelLayout& layout,
                  std::int64_t period_ns);

  const std::string& name() const { return config_.name; }
  const ActuatorConfig& config() const { return config_; }
  const ChannelLayout& layout() const { return layout_; }

  // One sample of the actuator's group. Returns true when it completed a hop (a decision).
  bool push(const realtime::Sample& sample, const EventPublisher& publish);
  // A sample that never arrived (missed cycle or ring drop) at source time t: a gap.
  void push_gap(double t, const EventPublisher& publish);

  void acknowledge(const EventPublisher& publish);
  // Adopt new alarm settings (reload) without losing state.
  void set_alarm_settings(const AlarmSettings& settings);
  // Adopt new transducer settings (reload): the plausibility checks keep their state.
  void set_transducers(const ActuatorConfig& config);
  // True when `other` can take over this monitor's learned state: the same state fingerprint
  // (state_store.hpp: channels, features, detector kind and options, sample period) and layout.
  bool same_pipeline(const ActuatorConfig& other, const ChannelLayout& other_layout) const;
  // What differs between this monitor's fingerprint and `other`'s, as "part: old -> new; ...".
  std::string fingerprint_change(const StateFingerprint& other) const;

  // Source time of the newest sample (NaN before the first).
  double newest_t() const { return newest_t_; }
  // Source time [s] from this monitor's first sample to the detector's first decision: the
  // features' first window plus the detector's own learning.
  double learning_seconds() const;
  // This monitor replaces `relearns - 1` earlier ones whose learning a reload invalidated; it
  // decides from source time `protected_from`.
  void note_relearning(std::uint64_t relearns, double protected_from);
  std::uint64_t relearns() const { return relearns_; }

  ActuatorStatus status() const;
  // The same into `out`, reusing its strings and channel list: allocates nothing once `out`
  // has held this actuator's status (the live page samples it every second).
  void status_into(ActuatorStatus& out) const;

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
  // Accounts one hop at source time t as judged or not, and announces a long spell without.
  void track_judging(double t, bool judged, detect::NotJudgedReason reason,
                     const EventPublisher& publish);
  io::Event alarm_event(io::EventKind kind, double t) const;
  // outage: every checked channel's raw value is missing in this sample.
  void check_sensor_faults(double t, bool outage, const EventPublisher& publish);
  // Whether the acquisition repeats samples (RepeatedSampleCheck); announces changes.
  bool check_repeats(double t, std::span<const double> acquired, const EventPublisher& publish);
  AlarmSettings effective(const AlarmSettings& configured) const;
  // Feeds the mode checks with a learning hop's indices; when learning ends, judges them and
  // announces a blind rig (and once more after a restart restored that verdict).
  void judge_mode_visibility(double t, const detect::Observation& observation,
                             const EventPublisher& publish);
  // When learning has just ended: a step the learning period's feature made (the detector's own
  // probe, or for a pressure-only detector the index probes here), announced as learned_change.
  void judge_learned_change(double t, const EventPublisher& publish);
  bool detection_blind() const {
    return watch_mode_ &&
           (mode_out_of_band_ || healthy_index_ratio_ < ModeVisibilityCheck::kBlindRatio);
  }

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
  HopMean hop_u_, hop_x_, hop_p1_, hop_p2_, hop_ps_, hop_temp_;
  std::size_t hop_samples_ = 0;
  // The hop's cleaned chamber pressures (Observation::p1_samples), `step` long.
  std::vector<double> hop_samples_p1_, hop_samples_p2_;
  // The hop's command and cleaned position the same way (Observation::u_samples, x_samples).
  std::vector<double> hop_samples_u_, hop_samples_x_;
  // Ring of the excitation signal (xref, else x) over the window, for Observation::x_activity.
  std::vector<double> activity_;
  std::size_t activity_next_ = 0;
  std::size_t activity_filled_ = 0;
  std::vector<double> index_input_;  // scratch: the index channels of one sample

  // Plausibility of the transducer channels the layout has, and the fault each has announced.
  struct Channel {
    capture::Role role;
    int index;
    detect::SensorPlausibility check;
    detect::SensorFault announced = detect::SensorFault::none;
    bool in_outage = false;  // its dropout began with every channel missing (not announced)
  };
  std::vector<Channel> channels_;
  RepeatedSampleCheck repeats_;
  double sample_rate_hz_;
  // Only for a detector that needs the hydraulic mode (watch_mode_): p1's and p2's checks.
  bool watch_mode_;
  std::array<ModeVisibilityCheck, 2> mode_checks_;
  // The described rig's mode (NaN for the paper's rig, whose mode is not in question) and
  // whether it lies outside what the index reads (ModeVisibilityCheck::readable_band).
  double rig_mode_hz_;
  bool mode_out_of_band_;
  bool mode_judged_ = false;
  double healthy_index_ratio_ = io::kNoValue;
  bool announce_blind_ = false;          // a restored blind verdict, announced at the next decision
  capture::ByRole<int> check_slot_{-1};  // by checked role, its index into channels_
  // u, xref and t delayed like the checked channels, so one sample stays one instant.
  struct Unchecked {
    double t, u, xref, ps, temp;
  };
  std::array<Unchecked, detect::SensorPlausibility::kDelay + 1> delay_{};
  std::uint64_t arrived_ = 0;        // samples pushed (raw)
  std::uint64_t fed_ = 0;            // delayed samples given to the features
  std::uint64_t blocked_until_ = 0;  // no detector update before this many samples are fed
  std::uint64_t suspended_decisions_ = 0;

  detect::Decision last_decision_;
  double last_t_ = io::kNoValue;
  double last_load_pressure_ = io::kNoValue;
  double last_temperature_ = io::kNoValue;
  double last_p1_ = io::kNoValue, last_p2_ = io::kNoValue;
  std::uint64_t decisions_ = 0;
  std::uint64_t gap_samples_ = 0;
  // Pressure-only detectors: the learned-change probes of p1 (and p2), fed while learning; only
  // judged when they saw the learning period from its start (not after a restored state).
  std::vector<detect::IndexStepProbe> index_probes_;
  bool probes_from_start_ = true;
  std::int64_t period_ns_;
  double newest_t_ = io::kNoValue;
  double protected_from_ = io::kNoValue;  // source time of the first decision (expected)
  std::uint64_t relearns_ = 0;
  double learning_ended_t_ = io::kNoValue;
  // Judging (ActuatorStatus::judged ...); not_judged_announced_: a not_judged event is out.
  bool judged_ = false;
  detect::NotJudgedReason not_judged_reason_ = detect::NotJudgedReason::learning;
  double not_judged_since_ = io::kNoValue;
  double judged_seconds_ = 0.0, decided_seconds_ = 0.0;
  bool not_judged_announced_ = false;
};

}  // namespace leakmon::pipeline
