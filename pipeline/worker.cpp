#include "pipeline/worker.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "realtime/acquisition_loop.hpp"

namespace leakmon::pipeline {

ChannelLayout layout_of(const ActuatorConfig& actuator, const std::vector<ChannelRef>& channels) {
  auto find = [&](const ChannelRef& ref) {
    if (!ref.present()) return -1;
    for (std::size_t i = 0; i < channels.size(); ++i) {
      if (channels[i].driver == ref.driver && channels[i].channel == ref.channel) {
        return static_cast<int>(i);
      }
    }
    return -1;
  };
  ChannelLayout layout;
  for (const capture::Role role : capture::kRoles)
    layout.index[role] = find(actuator.channels[role]);
  return layout;
}

Worker::Worker(const DaemonConfig& config, std::vector<GroupInput> groups,
               std::vector<io::EventSink*> sinks)
    : sinks_(std::move(sinks)) {
  for (auto& input : groups) {
    GroupState group;
    group.input = std::move(input);
    build_monitors(config, group, nullptr);
    if (!config.recording.directory.empty()) {
      // One driver: plain channel names, so `leakmon replay` finds p1, p2, u, x by default.
      const bool one_driver = std::all_of(
          group.input.channels.begin(), group.input.channels.end(),
          [&](const ChannelRef& c) { return c.driver == group.input.channels.front().driver; });
      std::vector<std::string> columns;
      for (const auto& c : group.input.channels)
        columns.push_back(one_driver ? c.channel : c.text());
      group.recorder = std::make_unique<CaptureRecorder>(
          group.input.name, columns, 1e9 / static_cast<double>(group.input.period_ns),
          config.recording);
    }
    groups_.push_back(std::move(group));
  }
}

Worker::~Worker() { flush(); }

void Worker::build_monitors(const DaemonConfig& config, GroupState& group,
                            std::vector<std::unique_ptr<ActuatorMonitor>>* previous) {
  std::vector<std::unique_ptr<ActuatorMonitor>> monitors;
  for (const auto& actuator : config.actuators) {
    const ChannelLayout layout = layout_of(actuator, group.input.channels);
    if (layout[capture::Role::p1] < 0) continue;  // another group's actuator
    std::unique_ptr<ActuatorMonitor> kept;
    const ActuatorMonitor* replaced = nullptr;  // same actuator, learned state no longer valid
    if (previous != nullptr) {
      for (auto& old : *previous) {
        if (!old || old->name() != actuator.name) continue;
        if (old->same_pipeline(actuator, layout)) {
          // Alarm thresholds and delays, transducer checks, outputs: the learning stays.
          kept = std::move(old);
          kept->set_alarm_settings(actuator.alarm);
          kept->set_transducers(actuator);
        } else {
          replaced = old.get();
        }
        break;
      }
    }
    if (kept) {
      monitors.push_back(std::move(kept));
      continue;
    }
    auto monitor = std::make_unique<ActuatorMonitor>(actuator, layout, group.input.period_ns);
    if (replaced != nullptr) {
      // What was learned depends on an option that changed: the new monitor learns again, and
      // until it is done a leak is not detected (and would become its baseline). Announced, so
      // that nobody believes the rig protected meanwhile.
      io::Event event;
      event.kind = io::EventKind::relearning;
      event.actuator = actuator.name;
      event.t = replaced->newest_t();
      event.learning_since = replaced->newest_t();
      event.protected_from = event.learning_since + monitor->learning_seconds();
      event.reason = replaced->fingerprint_change(monitor->fingerprint());
      event.message = fmt::format(
          "the learned state does not fit the reloaded options; learning again for {:.0f} s, "
          "no leak detection until then",
          monitor->learning_seconds());
      monitor->note_relearning(replaced->relearns() + 1, event.protected_from);
      publish_locked(event);
    }
    monitors.push_back(std::move(monitor));
  }
  group.monitors = std::move(monitors);
}

std::size_t Worker::drain(std::int64_t now_ns) {
  std::lock_guard lock(mutex_);
  std::size_t processed = 0;
  for (auto& group : groups_) {
    while (realtime::Sample* sample = group.input.ring->front()) {
      process(group, *sample, now_ns);
      group.input.ring->pop();
      ++processed;
    }
    if (group.recorder) group.recorder->maybe_flush(now_ns);
  }
  samples_ += processed;
  return processed;
}

void Worker::process(GroupState& group, const realtime::Sample& sample, std::int64_t now_ns) {
  const EventPublisher publish = [this](const io::Event& event) { publish_locked(event); };
  // Ticks that never arrived (missed cycles, ring drops) are gaps: they must invalidate the
  // windows that span them, not silently splice the signal together.
  if (group.started && sample.tick > group.next_tick) {
    const std::uint64_t missing = sample.tick - group.next_tick;
    const double period_s = static_cast<double>(group.input.period_ns) / 1e9;
    for (auto& monitor : group.monitors) {
      const std::uint64_t feed = std::min<std::uint64_t>(
          missing, monitor->config().features.window + monitor->config().features.step);
      for (std::uint64_t k = feed; k > 0; --k) {
        monitor->push_gap(sample.t - static_cast<double>(k) * period_s, publish);
      }
    }
  }
  group.started = true;
  group.next_tick = sample.tick + 1;

  if (group.recorder) group.recorder->record(sample);
  bool decided = false;
  for (auto& monitor : group.monitors) decided |= monitor->push(sample, publish);
  if (decided && sample.monotonic_ns > 0) {
    decision_latency_.record(realtime::monotonic_now_ns() - sample.monotonic_ns);
  }
  (void)now_ns;
}

void Worker::publish_locked(const io::Event& event) {
  ++events_;
  io::Event stamped = event;
  if (std::isnan(stamped.unix_time)) {
    stamped.unix_time =
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  }
  for (auto* sink : sinks_) sink->publish(stamped);
}

void Worker::publish(const io::Event& event) {
  std::lock_guard lock(mutex_);
  publish_locked(event);
}

std::size_t Worker::acknowledge(const std::string& actuator) {
  std::lock_guard lock(mutex_);
  const EventPublisher publish = [this](const io::Event& event) { publish_locked(event); };
  std::size_t matched = 0;
  for (auto& group : groups_) {
    for (auto& monitor : group.monitors) {
      if (!actuator.empty() && monitor->name() != actuator) continue;
      monitor->acknowledge(publish);
      ++matched;
    }
  }
  return matched;
}

void Worker::apply(const DaemonConfig& config, std::vector<io::EventSink*> sinks) {
  std::lock_guard lock(mutex_);
  for (auto& group : groups_) {
    auto previous = std::move(group.monitors);
    build_monitors(config, group, &previous);
  }
  sinks_ = std::move(sinks);
}

void Worker::flush() {
  std::lock_guard lock(mutex_);
  for (auto& group : groups_) {
    if (group.recorder) group.recorder->flush();
  }
  for (auto* sink : sinks_) sink->flush();
}

std::vector<ActuatorState> Worker::export_states() const {
  std::lock_guard lock(mutex_);
  std::vector<ActuatorState> states;
  for (const auto& group : groups_) {
    for (const auto& monitor : group.monitors) states.push_back(monitor->export_state());
  }
  return states;
}

void Worker::restore_states(const StateStore& store) {
  std::lock_guard lock(mutex_);
  for (auto& group : groups_) {
    for (auto& monitor : group.monitors) {
      io::Event event;
      event.actuator = monitor->name();
      StateStore::Loaded loaded = store.load(monitor->name(), monitor->fingerprint());
      if (loaded.state) {
        try {
          monitor->import_state(*loaded.state);
          event.kind = io::EventKind::state_restored;
          event.message =
              fmt::format("{}: resumed what was learned (alarm {})",
                          store.file_of(monitor->name()).string(), to_string(loaded.state->alarm));
        } catch (const detect::StateError& e) {
          loaded.warning = fmt::format("{}: saved state set aside: {}",
                                       store.file_of(monitor->name()).string(), e.what());
        }
      }
      if (!loaded.warning.empty()) {
        event.kind = io::EventKind::state_discarded;
        event.message = loaded.warning + "; learning afresh";
      } else if (!loaded.state) {
        continue;  // nothing saved yet: a first start
      }
      publish_locked(event);
    }
  }
}

std::vector<ActuatorStatus> Worker::status() const {
  std::lock_guard lock(mutex_);
  std::vector<ActuatorStatus> result;
  for (const auto& group : groups_) {
    for (const auto& monitor : group.monitors) result.push_back(monitor->status());
  }
  return result;
}

void Worker::status_into(std::vector<ActuatorStatus>& out) const {
  std::lock_guard lock(mutex_);
  std::size_t count = 0;
  for (const auto& group : groups_) count += group.monitors.size();
  out.resize(count);
  std::size_t i = 0;
  for (const auto& group : groups_) {
    for (const auto& monitor : group.monitors) monitor->status_into(out[i++]);
  }
}

std::uint64_t Worker::samples_processed() const {
  std::lock_guard lock(mutex_);
  return samples_;
}

std::uint64_t Worker::events_published() const {
  std::lock_guard lock(mutex_);
  return events_;
}

}  // namespace leakmon::pipeline
