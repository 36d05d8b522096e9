#include "pipeline/replay.hpp"

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <optional>
#include <thread>

#include "realtime/acquisition_loop.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/state_store.hpp"
#include "pipeline/worker.hpp"
#include "io/replay/replay_driver.hpp"

namespace leakmon::pipeline {
namespace {

constexpr const char* kCaptureDriver = "capture";

std::int64_t period_ns_of(const capture::Capture& capture) {
  const double rate = capture.sample_rate_hz();
  if (!(rate > 0.0) || !std::isfinite(rate)) {
    throw capture::CaptureError(fmt::format("{}: cannot tell the sample rate", capture.path));
  }
  return static_cast<std::int64_t>(std::llround(1e9 / rate));
}

// The configuration with the capture as its only driver.
DaemonConfig bind_to_capture(const capture::Capture& capture, const DaemonConfig& config) {
  DaemonConfig bound = config;
  bound.drivers = {DriverConfig{kCaptureDriver, "replay", std::nullopt}};
  GroupConfig group;
  group.name = "replay";
  group.period_ns = period_ns_of(capture);
  group.priority = 0;
  group.drivers = {kCaptureDriver};
  bound.groups = {group};
  bound.recording = {};
  for (auto& actuator : bound.actuators) {
    for (const capture::Role role : capture::kRoles) {
      ChannelRef& ref = actuator.channels[role];
      if (!ref.present()) continue;
      ref.driver = kCaptureDriver;
      if (ref.channel == "t" || !capture.has(ref.channel)) {
        const std::string message =
            fmt::format("the capture {} has no column '{}'", capture.path, ref.channel);
        if (ref.where) ref.where->fail(message);
        throw capture::CaptureError(message);
      }
    }
  }
  return bound;
}

}  // namespace

DaemonConfig default_replay_config(const capture::Capture& capture) {
  if (!capture.has("p1")) {
    throw capture::CaptureError(
        fmt::format("{}: the capture has no p1 column, which the default "
                    "replay configuration indexes",
                    capture.path));
  }
  DaemonConfig config;
  config.source = "built-in replay defaults";
  ActuatorConfig actuator;
  actuator.name = "actuator";
  for (const capture::Role role : capture::kRoles) {
    const std::string column(capture::to_string(role));
    if (capture.has(column))
      actuator.channels[role] = ChannelRef{kCaptureDriver, column, std::nullopt};
  }
  config.actuators.push_back(actuator);
  config.metrics.port = 0;
  return bind_to_capture(capture, config);
}

ReplayResult replay_capture(const capture::Capture& capture, const DaemonConfig& config,
                            const ReplayOptions& options) {
  // The driver keeps a shared_ptr; aliasing one that owns nothing avoids copying the capture.
  return replay_capture(std::shared_ptr<const capture::Capture>(std::shared_ptr<void>(), &capture),
                        config, options);
}

ReplayResult replay_capture(std::shared_ptr<const capture::Capture> capture,
                            const DaemonConfig& config, const ReplayOptions& options) {
  const DaemonConfig bound = bind_to_capture(*capture, config);
  const GroupConfig& group = bound.groups.front();

  io::ReplaySettings settings;
  settings.name = kCaptureDriver;
  settings.path = capture->path;
  io::ReplayDriver driver(settings, capture);
  driver.start();

  realtime::SpscRing<realtime::Sample> ring(group.ring_capacity);
  realtime::AcquisitionLoop loop(group.period_ns, {&driver}, ring);

  std::vector<ChannelRef> channels;
  for (const auto& name : driver.channels())
    channels.push_back({kCaptureDriver, name, std::nullopt});
  CollectingEventSink events;
  Worker worker(bound, {GroupInput{group.name, &ring, channels, group.period_ns}}, {&events});
  std::optional<StateStore> store;
  if (!options.state_directory.empty()) {
    store.emplace(options.state_directory);
    worker.restore_states(*store);
  }

  if (options.realtime) {
    std::atomic<bool> stop{false};
    std::thread acquisition([&] { loop.run(stop); });
    while (!loop.counters().end_of_stream.load(std::memory_order_acquire)) {
      worker.drain(realtime::monotonic_now_ns());
      std::this_thread::sleep_for(std::chrono::nanoseconds(group.period_ns));
    }
    stop.store(true, std::memory_order_release);
    acquisition.join();
  } else {
    // Simulated clock: tick k happens at k periods; when the ring is full the clock waits for
    // the worker, so nothing is dropped however fast the capture is read.
    io::Tick tick;
    while (true) {
      tick.monotonic_ns = static_cast<std::int64_t>(tick.index) * group.period_ns;
      if (loop.cycle_if_room(tick, 0)) {
        ++tick.index;
        continue;
      }
      if (loop.counters().end_of_stream.load(std::memory_order_relaxed)) break;
      worker.drain(0);
    }
  }
  worker.drain(0);
  std::vector<ActuatorState> learned = worker.export_states();
  if (store) {
    for (const auto& state : learned) store->save(state);
  }
  worker.flush();

  ReplayResult result;
  result.events = std::move(events.events);
  result.samples_read = loop.counters().samples_pushed.load() + loop.counters().ring_drops.load();
  result.samples_processed = worker.samples_processed();
  result.ring_drops = loop.counters().ring_drops.load();
  result.actuators = worker.status();
  result.learned = std::move(learned);
  return result;
}

}  // namespace leakmon::pipeline
