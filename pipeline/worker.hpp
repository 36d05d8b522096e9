// The worker: pops each sampling group's ring, records raw samples, and runs every actuator's
// monitor (features -> detector -> alarm), handing events to the sinks in order. Not real-time:
// it may allocate and lock. Other threads (metrics, control, reload) reach it through the
// methods below, which take its mutex.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pipeline/actuator_monitor.hpp"
#include "pipeline/capture_recorder.hpp"
#include "pipeline/config.hpp"
#include "realtime/latency_histogram.hpp"
#include "realtime/sample.hpp"
#include "realtime/spsc_ring.hpp"
#include "io/event.hpp"

namespace leakmon::pipeline {

struct GroupInput {
  std::string name;
  realtime::SpscRing<realtime::Sample>* ring = nullptr;
  std::vector<ChannelRef> channels;  // in Sample order
  std::int64_t period_ns = 2'000'000;
};

class Worker {
 public:
  // Builds a monitor per actuator (throws config::ConfigError / std::invalid_argument on a
  // detector that cannot be built) and a recorder per group when recording is configured.
  Worker(const DaemonConfig& config, std::vector<GroupInput> groups,
         std::vector<io::EventSink*> sinks);
  ~Worker();

  // Pops and processes everything queued now; returns the samples processed. `now_ns` is the
  // monotonic time used for flush timing and latency accounting.
  std::size_t drain(std::int64_t now_ns);

  // Daemon-wide events (driver faults, overruns, reloads) go through the same ordered path.
  void publish(const io::Event& event);
  // Acknowledge the alarms of `actuator` (empty: all). Returns how many actuators were known.
  std::size_t acknowledge(const std::string& actuator);
  // Reload: same groups, new actuators/alarms/sinks. Monitors whose signals, features and
  // detector are unchanged keep their learned state and alarm state.
  void apply(const DaemonConfig& config, std::vector<io::EventSink*> sinks);
  void flush();

  // Persistence across restarts (state_store.hpp), never from the real-time path: a snapshot of
  // what every actuator has learned, and resuming from `store` before the first sample. Each
  // actuator whose state was restored or set aside gets a state_restored / state_discarded
  // event (set aside: it learns afresh).
  std::vector<ActuatorState> export_states() const;
  void restore_states(const StateStore& store);

  std::vector<ActuatorStatus> status() const;
  // The same into `out`, reusing its storage: allocates nothing while the actuators are the
  // same as at the previous call (a reload that adds actuators allocates once).
  void status_into(std::vector<ActuatorStatus>& out) const;
  std::uint64_t samples_processed() const;
  std::uint64_t events_published() const;
  // From a sample's acquisition (monotonic) to the end of its decision and events.
  const realtime::LatencyHistogram& decision_latency() const { return decision_latency_; }

 private:
  struct GroupState {
    GroupInput input;
    std::vector<std::unique_ptr<ActuatorMonitor>> monitors;
    std::unique_ptr<CaptureRecorder> recorder;
    std::uint64_t next_tick = 0;
    bool started = false;
  };
  void build_monitors(const DaemonConfig& config, GroupState& group,
                      std::vector<std::unique_ptr<ActuatorMonitor>>* previous);
  void process(GroupState& group, const realtime::Sample& sample, std::int64_t now_ns);
  void publish_locked(const io::Event& event);

  mutable std::mutex mutex_;
  std::vector<GroupState> groups_;
  std::vector<io::EventSink*> sinks_;
  std::uint64_t samples_ = 0;
  std::uint64_t events_ = 0;
  realtime::LatencyHistogram decision_latency_;
};

// Where each role of `actuator` sits among `channels`.
ChannelLayout layout_of(const ActuatorConfig& actuator, const std::vector<ChannelRef>& channels);

}  // namespace leakmon::pipeline
