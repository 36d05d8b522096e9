#include "daemon/daemon.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <ctime>

#include "daemon/driver_registry.hpp"
#include "daemon/event_log.hpp"
#include "daemon/output_registry.hpp"

namespace leakmon::daemon {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;
// Thread stacks: small, because mlockall(MCL_FUTURE) makes every stack page resident.
constexpr std::size_t kThreadStackBytes = 1 << 20;

sigset_t control_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  return set;
}

std::string yaml_text(const std::optional<config::ConfigNode>& node) {
  if (!node) return {};
  YAML::Emitter out;
  out << node->yaml();
  return out.c_str();
}

// What a reload cannot change without restarting acquisition.
std::string acquisition_signature(const DaemonConfig& config) {
  std::string text;
  for (const auto& d : config.drivers)
    text += fmt::format("driver {}\n{}\n", d.name, yaml_text(d.node));
  for (const auto& g : config.groups) {
    text += fmt::format("group {} {} {} {} [{}] [{}]\n", g.name, g.period_ns, g.priority,
                        g.ring_capacity, fmt::join(g.drivers, ","), fmt::join(g.cpus, ","));
  }
  text += fmt::format("recording {} {} {} {}\n", config.recording.directory,
                      config.recording.rotate_seconds, config.recording.keep_files,
                      config.recording.flush_seconds);
  text += fmt::format("metrics {}:{}\n", config.metrics.address, config.metrics.port);
  text += fmt::format("worker {} {}\n", config.worker_priority, config.worker_poll_ns);
  text += fmt::format("realtime {}\n", config.cpu_wakeup_latency_us);
  text += fmt::format("state {}\n", config.state.directory);
  return text;
}

std::string label(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

void histogram(std::string& out, std::string_view name, std::string_view labels,
               const LatencyHistogram& h) {
  static constexpr double kBucketsSeconds[] = {10e-6, 20e-6, 50e-6, 100e-6, 200e-6, 500e-6,
                                               1e-3,  2e-3,  5e-3,  10e-3,  20e-3};
  const std::string sep = labels.empty() ? "" : ",";
  for (double le : kBucketsSeconds) {
    out += fmt::format("{}_bucket{{{}{}le=\"{}\"}} {}\n", name, labels, sep, le,
                       h.count_below(static_cast<std::int64_t>(std::llround(le * 1e9))));
  }
  out += fmt::format("{}_bucket{{{}{}le=\"+Inf\"}} {}\n", name, labels, sep, h.count());
  out += fmt::format("{}_sum{{{}}} {}\n", name, labels, static_cast<double>(h.sum_ns()) / 1e9);
  out += fmt::format("{}_count{{{}}} {}\n", name, labels, h.count());
}

std::string number(double v) { return std::isfinite(v) ? fmt::format("{}", v) : "NaN"; }

}  // namespace

Daemon::Daemon(std::string config_path) : config_path_(std::move(config_path)) {}

Daemon::~Daemon() { stop(); }

std::vector<std::unique_ptr<EventSink>> Daemon::build_sinks(const DaemonConfig& config) const {
  std::vector<std::unique_ptr<EventSink>> sinks;
  sinks.push_back(std::make_unique<LogEventSink>());
  if (!config.event_log.empty()) sinks.push_back(std::make_unique<JsonlEventLog>(config.event_log));
  for (const auto& node : config.outputs) sinks.push_back(make_output(node));
  return sinks;
}

std::vector<EventSink*> Daemon::raw(const std::vector<std::unique_ptr<EventSink>>& sinks) {
  std::vector<EventSink*> out;
  for (const auto& s : sinks) out.push_back(s.get());
  return out;
}

void Daemon::start() {
  config_ = check_config(config_path_);
  spdlog::info("configuration {}: {} driver(s), {} sampling group(s), {} actuator(s)", config_path_,
               config_.drivers.size(), config_.groups.size(), config_.actuators.size());

  // Threads inherit the blocked control signals: only the main thread receives them.
  const sigset_t signals = control_signals();
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, kThreadStackBytes);
  pthread_setattr_default_np(&attr);
  pthread_attr_destroy(&attr);
  if (const std::string warning = lock_process_memory(); !warning.empty()) {
    spdlog::warn("{}", warning);
  }
  if (config_.cpu_wakeup_latency_us >= 0) {
    cpu_latency_ = CpuLatencyRequest(config_.cpu_wakeup_latency_us);
    if (!cpu_latency_.held()) spdlog::warn("{}", cpu_latency_.warning());
  }

  for (const auto& driver : config_.drivers) {
    drivers_.push_back(make_driver(*driver.node));
    drivers_.back()->start();
    driver_watch_.emplace_back();
  }
  std::vector<GroupInput> inputs;
  for (const auto& group_config : config_.groups) {
    auto group = std::make_unique<Group>();
    group->config = group_config;
    std::vector<ChannelRef> channels;
    for (const auto& name : group_config.drivers) {
      for (std::size_t i = 0; i < config_.drivers.size(); ++i) {
        if (config_.drivers[i].name != name) continue;
        group->drivers.push_back(drivers_[i].get());
        for (const auto& channel : drivers_[i]->channels()) {
          channels.push_back(ChannelRef{name, channel, std::nullopt});
        }
      }
    }
    group->ring = std::make_unique<SpscRing<Sample>>(group_config.ring_capacity);
    group->loop =
        std::make_unique<AcquisitionLoop>(group_config.period_ns, group->drivers, *group->ring);
    inputs.push_back(
        GroupInput{group_config.name, group->ring.get(), channels, group_config.period_ns});
    groups_.push_back(std::move(group));
  }
  reported_overruns_.assign(groups_.size(), 0);
  sinks_ = build_sinks(config_);
  worker_ = std::make_unique<Worker>(config_, inputs, raw(sinks_));
  // What was learned before a restart comes back before the first sample is acquired.
  if (!config_.state.directory.empty()) {
    state_store_ = std::make_unique<StateStore>(config_.state.directory);
    worker_->restore_states(*state_store_);
    spdlog::info("learned state kept under {} (saved every {} s and at shutdown)",
                 config_.state.directory, config_.state.save_seconds);
  }

  std::vector<std::string> worker_warnings;
  std::atomic<bool> worker_ready{false};
  worker_thread_ = std::thread([this, &worker_warnings, &worker_ready] {
    const std::int64_t poll_ns = config_.worker_poll_ns;
    worker_warnings = make_thread_realtime(config_.worker_priority, {}).warnings;
    worker_ready.store(true, std::memory_order_release);
    while (!stop_worker_.load(std::memory_order_acquire)) {
      if (worker_->drain(monotonic_now_ns()) == 0) {
        std::this_thread::sleep_for(std::chrono::nanoseconds(poll_ns));
      }
    }
  });
  for (auto& group : groups_) {
    Group* g = group.get();
    g->thread = std::thread([this, g] {
      g->realtime = make_thread_realtime(g->config.priority, g->config.cpus);
      g->realtime_ready.store(true, std::memory_order_release);
      g->loop->run(stop_acquisition_);
    });
  }
  // Start-up warnings are logged here, by the main thread, never by the loops.
  while (!worker_ready.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (const auto& warning : worker_warnings) spdlog::warn("worker: {}", warning);
  for (auto& group : groups_) {
    while (!group->realtime_ready.load(std::memory_order_acquire)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    for (const auto& warning : group->realtime.warnings) {
      spdlog::warn("sampling group {}: {}", group->config.name, warning);
    }
    spdlog::info("sampling group {}: {} channel(s) every {} ms, {}", group->config.name,
                 group->loop->channel_count(), static_cast<double>(group->config.period_ns) / 1e6,
                 group->realtime.fifo ? fmt::format("SCHED_FIFO {}", group->config.priority)
                                      : std::string("normal scheduling"));
  }
  if (config_.metrics.port != 0) {
    endpoint_ = std::make_unique<HttpEndpoint>(
        config_.metrics.address, config_.metrics.port,
        [this](const HttpRequest& request) { return handle(request); });
    spdlog::info("metrics and control on http://{}:{}/metrics", config_.metrics.address,
                 endpoint_->port());
  }
  if (!config_.event_log.empty()) spdlog::info("events: {}", config_.event_log);
  if (!config_.recording.directory.empty()) {
    spdlog::info("recording raw samples under {}", config_.recording.directory);
  }
  started_ns_ = monotonic_now_ns();
  last_state_save_ns_ = started_ns_;
}

void Daemon::save_state() {
  if (!state_store_ || !worker_) return;
  for (const auto& state : worker_->export_states()) {
    try {
      state_store_->save(state);
    } catch (const std::exception& e) {
      spdlog::error("cannot save the learned state: {}", e.what());
      Event event;
      event.kind = EventKind::state_save_failed;
      event.actuator = state.actuator;
      event.message = e.what();
      worker_->publish(event);
    }
  }
}

void Daemon::stop() {
  if (!worker_) return;
  stop_acquisition_.store(true, std::memory_order_release);
  for (auto& group : groups_) {
    if (group->thread.joinable()) group->thread.join();
  }
  for (auto& driver : drivers_) driver->stop();
  stop_worker_.store(true, std::memory_order_release);
  if (worker_thread_.joinable()) worker_thread_.join();
  worker_->drain(monotonic_now_ns());  // whatever the loops pushed last
  save_state();
  worker_->flush();
  endpoint_.reset();
  std::uint64_t pushed = 0, drops = 0;
  for (const auto& group : groups_) {
    pushed += group->loop->counters().samples_pushed.load();
    drops += group->loop->counters().ring_drops.load();
  }
  spdlog::info("stopped: {} samples acquired, {} processed, {} dropped, {} events", pushed,
               worker_->samples_processed(), drops, worker_->events_published());
  worker_.reset();
  sinks_.clear();
}

bool Daemon::all_sources_ended() const {
  for (const auto& group : groups_) {
    if (!group->loop->counters().end_of_stream.load(std::memory_order_acquire)) return false;
  }
  return !groups_.empty();
}

bool Daemon::making_progress(std::int64_t now_ns) {
  // Every loop has cycled within the last second (or ten periods, if longer), and the worker
  // keeps up (it processed something, or nothing is queued).
  for (const auto& group : groups_) {
    const auto& counters = group->loop->counters();
    if (counters.end_of_stream.load()) continue;
    const std::int64_t limit = std::max<std::int64_t>(kSecond, 10 * group->config.period_ns);
    if (now_ns - counters.last_cycle_ns.load(std::memory_order_relaxed) > limit) return false;
  }
  const std::uint64_t processed = worker_->samples_processed();
  bool queued = false;
  for (const auto& group : groups_) queued |= !group->ring->empty();
  const bool worker_ok = processed != last_processed_ || !queued;
  last_processed_ = processed;
  return worker_ok;
}

void Daemon::housekeeping(std::int64_t now_ns) {
  if (state_store_ &&
      now_ns - last_state_save_ns_ >= static_cast<std::int64_t>(config_.state.save_seconds * 1e9)) {
    save_state();
    last_state_save_ns_ = now_ns;
  }
  // Overruns: at most one warning (and one event) per second for all groups.
  if (now_ns - last_overrun_warning_ns_ >= kSecond) {
    for (std::size_t i = 0; i < groups_.size(); ++i) {
      const auto& counters = groups_[i]->loop->counters();
      const std::uint64_t overruns = counters.overruns.load();
      if (overruns == reported_overruns_[i]) continue;
      Event event;
      event.kind = EventKind::overrun;
      event.channel = groups_[i]->config.name;
      event.message =
          fmt::format("{} overrun(s), {} missed cycle(s) in total, {} ring drop(s)", overruns,
                      counters.missed_cycles.load(), counters.ring_drops.load());
      worker_->publish(event);
      reported_overruns_[i] = overruns;
      last_overrun_warning_ns_ = now_ns;
    }
  }
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    const io::DriverHealth health = drivers_[i]->health();
    DriverWatch& watch = driver_watch_[i];
    if (health.state != watch.state) {
      Event event;
      event.kind = health.state == "ok" ? EventKind::driver_recovered : EventKind::driver_fault;
      event.channel = drivers_[i]->name();
      event.message = fmt::format("state {} -> {}{}{}", watch.state, health.state,
                                  health.last_error.empty() ? "" : ": ", health.last_error);
      worker_->publish(event);
      watch.state = health.state;
    }
    watch.errors = health.errors;
  }
  const auto interval = notifier_.watchdog_interval();
  if (interval.count() > 0 && now_ns - last_watchdog_ns_ >= interval.count() * 1000 / 4) {
    if (making_progress(now_ns)) notifier_.watchdog();
    last_watchdog_ns_ = now_ns;
  }
}

void Daemon::reload() {
  notifier_.reloading();
  spdlog::info("SIGHUP: reloading {}", config_path_);
  Event event;
  try {
    DaemonConfig next = check_config(config_path_);
    if (acquisition_signature(next) != acquisition_signature(config_)) {
      throw config::ConfigError(fmt::format(
          "{}: drivers, sampling groups, recording, metrics, worker, realtime or state directory "
          "changed; these "
          "need a restart "
          "(systemctl restart leakmon)",
          config_path_));
    }
    auto sinks = build_sinks(next);
    worker_->apply(next, raw(sinks));
    sinks_.swap(sinks);  // the old sinks go only after the worker stopped using them
    config_ = std::move(next);
    ++reloads_;
    last_reload_ok_ = true;
    event.kind = EventKind::config_reloaded;
    event.message = config_path_;
  } catch (const std::exception& e) {
    ++reload_failures_;
    last_reload_ok_ = false;
    spdlog::error("reload rejected, the running configuration stays: {}", e.what());
    event.kind = EventKind::config_rejected;
    event.message = e.what();
  }
  last_reload_unix_ = static_cast<std::int64_t>(std::time(nullptr));
  worker_->publish(event);
  notifier_.ready(last_reload_ok_ ? "running (configuration reloaded)"
                                  : "running (reload rejected, see log)");
}

int Daemon::run(double duration_s) {
  start();
  const std::int64_t deadline_ns =
      duration_s > 0 ? started_ns_ + static_cast<std::int64_t>(duration_s * 1e9) : 0;
  notifier_.ready(fmt::format("running: {} actuator(s), {} sampling group(s)",
                              config_.actuators.size(), groups_.size()));
  spdlog::info("running");

  const sigset_t signals = control_signals();
  const std::int64_t watchdog_ns = notifier_.watchdog_interval().count() * 1000;
  const std::int64_t wait_ns =
      watchdog_ns > 0 ? std::min<std::int64_t>(kSecond / 4, watchdog_ns / 4) : kSecond / 4;
  while (true) {
    const timespec timeout{0, static_cast<long>(wait_ns)};
    const int signal = sigtimedwait(&signals, nullptr, &timeout);
    if (signal == SIGTERM || signal == SIGINT) {
      spdlog::info("{}: stopping", signal == SIGTERM ? "SIGTERM" : "SIGINT");
      break;
    }
    if (signal == SIGHUP) reload();
    housekeeping(monotonic_now_ns());
    if (all_sources_ended()) {
      spdlog::info("every source has ended: stopping");
      break;
    }
    if (deadline_ns > 0 && monotonic_now_ns() >= deadline_ns) {
      spdlog::info("--duration {} s reached: stopping", duration_s);
      break;
    }
  }
  notifier_.stopping();
  stop();
  return 0;
}

HttpResponse Daemon::handle(const HttpRequest& request) {
  if (request.path == "/metrics" && request.method == "GET")
    return {200, "text/plain; version=0.0.4; charset=utf-8", metrics_text()};
  if (request.path == "/status" && request.method == "GET")
    return {200, "text/plain; charset=utf-8", status_text()};
  if (request.path == "/ack") {
    if (request.method != "POST") return {405, "text/plain", "use POST /ack?actuator=NAME\n"};
    std::string actuator;
    if (request.query.rfind("actuator=", 0) == 0) actuator = request.query.substr(9);
    const std::size_t matched = worker_->acknowledge(actuator);
    if (matched == 0) return {404, "text/plain", fmt::format("no actuator '{}'\n", actuator)};
    return {200, "text/plain", fmt::format("acknowledged {} actuator(s)\n", matched)};
  }
  return {404, "text/plain", "try /metrics, /status or POST /ack\n"};
}

std::string Daemon::metrics_text() const {
  std::string out;
  out += "# HELP leakmon_build_info leakmon version\n# TYPE leakmon_build_info gauge\n";
  out += fmt::format("leakmon_build_info{{version=\"{}\"}} 1\n", LEAKMON_VERSION);

  out +=
      "# HELP leakmon_loop_wakeup_latency_seconds acquisition loop wake-up minus schedule\n"
      "# TYPE leakmon_loop_wakeup_latency_seconds histogram\n";
  for (const auto& g : groups_) {
    histogram(out, "leakmon_loop_wakeup_latency_seconds",
              fmt::format("group=\"{}\"", label(g->config.name)),
              g->loop->counters().wakeup_latency);
  }
  auto counter = [&](std::string_view name, std::string_view help, std::string_view type,
                     auto value_of) {
    out += fmt::format("# HELP {} {}\n# TYPE {} {}\n", name, help, name, type);
    for (const auto& g : groups_) {
      out += fmt::format("{}{{group=\"{}\"}} {}\n", name, label(g->config.name), value_of(*g));
    }
  };
  counter("leakmon_loop_cycles_total", "acquisition cycles run", "counter",
          [](const Group& g) { return g.loop->counters().cycles.load(); });
  counter("leakmon_loop_overruns_total", "late wake-ups that skipped a period", "counter",
          [](const Group& g) { return g.loop->counters().overruns.load(); });
  counter("leakmon_loop_missed_cycles_total", "periods skipped by overruns", "counter",
          [](const Group& g) { return g.loop->counters().missed_cycles.load(); });
  counter("leakmon_ring_drops_total", "samples dropped because the ring was full", "counter",
          [](const Group& g) { return g.loop->counters().ring_drops.load(); });
  counter("leakmon_ring_high_water", "most samples ever queued in the ring", "gauge",
          [](const Group& g) { return g.loop->counters().ring_high_water.load(); });
  counter("leakmon_ring_capacity", "ring capacity in samples", "gauge",
          [](const Group& g) { return g.ring->capacity(); });
  counter("leakmon_loop_realtime", "1 when the loop runs SCHED_FIFO", "gauge",
          [](const Group& g) { return g.realtime.fifo ? 1 : 0; });

  out +=
      "# HELP leakmon_cpu_wakeup_latency_request_held 1 while the CPU wake-up latency request "
      "(/dev/cpu_dma_latency) is held\n"
      "# TYPE leakmon_cpu_wakeup_latency_request_held gauge\n";
  out += fmt::format("leakmon_cpu_wakeup_latency_request_held {}\n", cpu_latency_.held() ? 1 : 0);
  out +=
      "# HELP leakmon_samples_processed_total samples the worker consumed\n"
      "# TYPE leakmon_samples_processed_total counter\n";
  out += fmt::format("leakmon_samples_processed_total {}\n", worker_->samples_processed());
  out += "# HELP leakmon_events_total events published\n# TYPE leakmon_events_total counter\n";
  out += fmt::format("leakmon_events_total {}\n", worker_->events_published());
  out +=
      "# HELP leakmon_decision_latency_seconds sample acquisition to decision and events\n"
      "# TYPE leakmon_decision_latency_seconds histogram\n";
  histogram(out, "leakmon_decision_latency_seconds", "", worker_->decision_latency());

  const auto actuators = worker_->status();
  out +=
      "# HELP leakmon_index_pascal newest wavelet index (db8 level-2 detail RMS)\n"
      "# TYPE leakmon_index_pascal gauge\n";
  for (const auto& a : actuators) {
    out += fmt::format("leakmon_index_pascal{{actuator=\"{}\",channel=\"p1\"}} {}\n", label(a.name),
                       number(a.index_p1));
    if (std::isfinite(a.index_p2)) {
      out += fmt::format("leakmon_index_pascal{{actuator=\"{}\",channel=\"p2\"}} {}\n",
                         label(a.name), number(a.index_p2));
    }
  }
  out +=
      "# HELP leakmon_detector_score newest detector score\n# TYPE leakmon_detector_score gauge\n";
  for (const auto& a : actuators) {
    out += fmt::format("leakmon_detector_score{{actuator=\"{}\",detector=\"{}\"}} {}\n",
                       label(a.name), label(a.detector), number(a.score));
  }
  out +=
      "# HELP leakmon_detector_learning 1 while the detector learns the healthy baseline\n"
      "# TYPE leakmon_detector_learning gauge\n";
  for (const auto& a : actuators) {
    out += fmt::format("leakmon_detector_learning{{actuator=\"{}\"}} {}\n", label(a.name),
                       a.learning ? 1 : 0);
  }
  out +=
      "# HELP leakmon_alarm_active 1 while the alarm is annunciated\n"
      "# TYPE leakmon_alarm_active gauge\n";
  for (const auto& a : actuators) {
    out += fmt::format("leakmon_alarm_active{{actuator=\"{}\",alarm=\"{}\",state=\"{}\"}} {}\n",
                       label(a.name), label(a.alarm), to_string(a.state),
                       a.state == AlarmState::normal ? 0 : 1);
  }
  out +=
      "# HELP leakmon_sensor_status NAMUR NE 107 status of each transducer channel (1: current)\n"
      "# TYPE leakmon_sensor_status gauge\n";
  std::string spikes =
      "# HELP leakmon_sensor_spikes_rejected_total isolated spikes replaced before the index\n"
      "# TYPE leakmon_sensor_spikes_rejected_total counter\n";
  for (const auto& a : actuators) {
    for (const auto& c : a.channels) {
      for (auto status :
           {io::DeviceStatus::ok, io::DeviceStatus::failure, io::DeviceStatus::function_check,
            io::DeviceStatus::out_of_specification, io::DeviceStatus::maintenance_required}) {
        out += fmt::format(
            "leakmon_sensor_status{{actuator=\"{}\",channel=\"{}\",status=\"{}\"}} {}\n",
            label(a.name), c.channel, io::to_string(status), c.status == status ? 1 : 0);
      }
      spikes +=
          fmt::format("leakmon_sensor_spikes_rejected_total{{actuator=\"{}\",channel=\"{}\"}} {}\n",
                      label(a.name), c.channel, c.spikes_rejected);
    }
  }
  out += spikes;
  out +=
      "# HELP leakmon_detector_suspended 1 while a faulty channel holds the leak decision\n"
      "# TYPE leakmon_detector_suspended gauge\n";
  for (const auto& a : actuators) {
    out += fmt::format("leakmon_detector_suspended{{actuator=\"{}\"}} {}\n", label(a.name),
                       a.suspended ? 1 : 0);
  }
  out +=
      "# HELP leakmon_driver_errors_total driver communication errors\n"
      "# TYPE leakmon_driver_errors_total counter\n";
  std::string up, reconnects, stale;
  for (const auto& d : drivers_) {
    const auto health = d->health();
    out += fmt::format("leakmon_driver_errors_total{{driver=\"{}\"}} {}\n", label(d->name()),
                       health.errors);
    up += fmt::format("leakmon_driver_up{{driver=\"{}\",state=\"{}\"}} {}\n", label(d->name()),
                      label(health.state), health.state == "ok" ? 1 : 0);
    reconnects += fmt::format("leakmon_driver_reconnects_total{{driver=\"{}\"}} {}\n",
                              label(d->name()), health.reconnects);
    stale += fmt::format("leakmon_driver_stale_values_total{{driver=\"{}\"}} {}\n",
                         label(d->name()), health.stale_values);
  }
  out +=
      "# HELP leakmon_driver_up 1 when the driver reports state ok\n# TYPE leakmon_driver_up "
      "gauge\n" +
      up;
  out +=
      "# HELP leakmon_driver_reconnects_total driver reconnects\n# TYPE "
      "leakmon_driver_reconnects_total counter\n" +
      reconnects;
  out +=
      "# HELP leakmon_driver_stale_values_total reads that gave a gap because the value was too "
      "old\n# TYPE leakmon_driver_stale_values_total counter\n" +
      stale;

  out +=
      "# HELP leakmon_config_reload_success 1 when the last reload (or start) succeeded\n"
      "# TYPE leakmon_config_reload_success gauge\n";
  out += fmt::format("leakmon_config_reload_success {}\n", last_reload_ok_.load() ? 1 : 0);
  out +=
      "# HELP leakmon_config_reloads_total reloads applied\n# TYPE leakmon_config_reloads_total "
      "counter\n";
  out += fmt::format("leakmon_config_reloads_total {}\n", reloads_.load());
  out +=
      "# HELP leakmon_config_reload_failures_total reloads rejected\n# TYPE "
      "leakmon_config_reload_failures_total counter\n";
  out += fmt::format("leakmon_config_reload_failures_total {}\n", reload_failures_.load());
  out +=
      "# HELP leakmon_config_last_reload_timestamp_seconds unix time of the last reload attempt\n"
      "# TYPE leakmon_config_last_reload_timestamp_seconds gauge\n";
  out += fmt::format("leakmon_config_last_reload_timestamp_seconds {}\n", last_reload_unix_.load());
  return out;
}

std::string Daemon::status_text() const {
  std::string out =
      fmt::format("leakmon {} running {:.0f} s, configuration {}\n", LEAKMON_VERSION,
                  static_cast<double>(monotonic_now_ns() - started_ns_) / 1e9, config_path_);
  out += fmt::format("last reload: {}\n", last_reload_ok_.load() ? "ok" : "REJECTED (see log)");
  for (const auto& g : groups_) {
    const auto& c = g->loop->counters();
    out += fmt::format(
        "group {}: {} cycles, wake-up latency avg {:.1f} us max {:.1f} us, {} overruns, {} missed, "
        "{} ring drops (high water {}/{}), {}\n",
        g->config.name, c.cycles.load(), c.wakeup_latency.mean_ns() / 1e3,
        static_cast<double>(c.wakeup_latency.max_ns()) / 1e3, c.overruns.load(),
        c.missed_cycles.load(), c.ring_drops.load(), c.ring_high_water.load(), g->ring->capacity(),
        g->realtime.fifo ? "SCHED_FIFO" : "normal scheduling");
  }
  for (const auto& d : drivers_) {
    const auto health = d->health();
    out += fmt::format("driver {}: {}{}{} ({} errors)\n", d->name(), health.state,
                       health.last_error.empty() ? "" : ": ", health.last_error, health.errors);
  }
  for (const auto& a : worker_->status()) {
    out += fmt::format(
        "actuator {}: alarm {} {}, index p1 {:.2f} kPa, score {:.3g}, baseline {:.2f} "
        "kPa{}, detector {}, t {:.2f} s\n",
        a.name, a.alarm, to_string(a.state), a.index_p1 / 1e3, a.score, a.baseline / 1e3,
        a.learning ? " (learning)" : "", a.detector, a.t);
    for (const auto& c : a.channels) {
      out += fmt::format("  channel {}: {}{}{}, {} spikes rejected\n", c.channel,
                         io::to_string(c.status), c.fault == detect::SensorFault::none ? "" : " ",
                         c.fault == detect::SensorFault::none ? "" : detect::to_string(c.fault),
                         c.spikes_rejected);
    }
    if (a.suspended) out += "  leak decision suspended (sensor fault)\n";
  }
  return out;
}

}  // namespace leakmon::daemon
