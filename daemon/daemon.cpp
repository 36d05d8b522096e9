#include "daemon/daemon.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <limits>

#include "daemon/driver_registry.hpp"
#include "daemon/output_registry.hpp"
#include "daemon/routes.hpp"
#include "http/http_router.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/learning_report.hpp"
#include "views/metrics_text.hpp"
#include "views/status_json.hpp"

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
  text += fmt::format("metrics {}:{} trend {} {}\n", config.metrics.address, config.metrics.port,
                      config.metrics.trend_seconds, config.metrics.trend_interval_s);
  text += fmt::format("worker {} {}\n", config.worker_priority, config.worker_poll_ns);
  text += fmt::format("realtime {}\n", config.cpu_wakeup_latency_us);
  text += fmt::format("state {}\n", config.state.directory);
  return text;
}

}  // namespace

Daemon::Daemon(std::string config_path) : config_path_(std::move(config_path)) {}

Daemon::~Daemon() { stop(); }

std::vector<std::unique_ptr<io::EventSink>> Daemon::build_sinks(const DaemonConfig& config) const {
  std::vector<std::unique_ptr<io::EventSink>> sinks;
  sinks.push_back(std::make_unique<pipeline::LogEventSink>());
  if (!config.event_log.empty())
    sinks.push_back(std::make_unique<pipeline::JsonlEventLog>(config.event_log));
  for (const auto& node : config.outputs) sinks.push_back(make_output(node));
  if (operator_view_) sinks.push_back(operator_view_->event_sink());  // the page's last events
  return sinks;
}

std::vector<io::EventSink*> Daemon::raw(const std::vector<std::unique_ptr<io::EventSink>>& sinks) {
  std::vector<io::EventSink*> out;
  for (const auto& s : sinks) out.push_back(s.get());
  return out;
}

void Daemon::attach_readings(const std::vector<std::unique_ptr<io::EventSink>>& sinks,
                             bool attach) const {
  io::ReadingSource source;
  if (attach) {
    source = [this] {
      views::ServiceSnapshot snapshot;
      fill_actuators(snapshot);  // all a feature message reads
      std::vector<io::ActuatorReading> readings;
      for (const auto& a : snapshot.actuators) {
        readings.push_back({a.name, views::features_json(snapshot, a)});
      }
      return readings;
    };
  }
  for (const auto& sink : sinks) sink->attach_readings(source);
}

void Daemon::start() {
  config_ = check_config(config_path_);
  spdlog::info("configuration {}: {} driver(s), {} sampling group(s), {} actuator(s)", config_path_,
               config_.drivers.size(), config_.groups.size(), config_.actuators.size());
  for (const auto& warning : config_.warnings) spdlog::warn("{}", warning);

  // Threads inherit the blocked control signals: only the main thread receives them.
  const sigset_t signals = control_signals();
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, kThreadStackBytes);
  pthread_setattr_default_np(&attr);
  pthread_attr_destroy(&attr);
  if (const std::string warning = realtime::lock_process_memory(); !warning.empty()) {
    spdlog::warn("{}", warning);
  }
  if (config_.cpu_wakeup_latency_us >= 0) {
    cpu_latency_ = realtime::CpuLatencyRequest(config_.cpu_wakeup_latency_us);
    if (!cpu_latency_.held()) spdlog::warn("{}", cpu_latency_.warning());
  }

  for (const auto& driver : config_.drivers) {
    drivers_.push_back(make_driver(*driver.node));
    drivers_.back()->start();
    driver_watch_.emplace_back();
  }
  std::vector<pipeline::GroupInput> inputs;
  for (const auto& group_config : config_.groups) {
    auto group = std::make_unique<Group>();
    group->config = group_config;
    std::vector<pipeline::ChannelRef> channels;
    for (const auto& name : group_config.drivers) {
      for (std::size_t i = 0; i < config_.drivers.size(); ++i) {
        if (config_.drivers[i].name != name) continue;
        group->drivers.push_back(drivers_[i].get());
        for (const auto& channel : drivers_[i]->channels()) {
          channels.push_back(pipeline::ChannelRef{name, channel, std::nullopt});
        }
      }
    }
    group->ring =
        std::make_unique<realtime::SpscRing<realtime::Sample>>(group_config.ring_capacity);
    group->loop = std::make_unique<realtime::AcquisitionLoop>(group_config.period_ns,
                                                              group->drivers, *group->ring);
    inputs.push_back(pipeline::GroupInput{group_config.name, group->ring.get(), channels,
                                          group_config.period_ns});
    groups_.push_back(std::move(group));
  }
  reported_overruns_.assign(groups_.size(), 0);
  if (config_.metrics.port != 0) {
    std::vector<std::string> group_names;
    for (const auto& group : groups_) group_names.push_back(group->config.name);
    operator_view_ = std::make_unique<views::OperatorView>(config_, group_names);
    // The page shows what happened before a restart, starting with the log's newest events.
    if (!config_.event_log.empty()) operator_view_->restore_events(config_.event_log);
  }
  sinks_ = build_sinks(config_);
  worker_ = std::make_unique<pipeline::Worker>(config_, inputs, raw(sinks_));
  attach_readings(sinks_, true);
  // What was learned before a restart comes back before the first sample is acquired.
  if (!config_.state.directory.empty()) {
    state_store_ = std::make_unique<pipeline::StateStore>(config_.state.directory);
    worker_->restore_states(*state_store_);
    // A file that fits the configuration is what the detector resumed from: its age is the
    // learned state's until the next save.
    const auto fingerprints = pipeline::state_fingerprints(config_);
    const auto listing = state_store_->list();
    const std::lock_guard lock(state_saved_mutex_);
    for (const auto& state : listing.states) {
      for (const auto& [actuator, fingerprint] : fingerprints) {
        if (actuator == state.actuator && fingerprint == state.fingerprint) {
          state_saved_unix_[actuator] = state.saved_unix;
        }
      }
    }
    if (operator_view_) {
      const double unix_now =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count();
      for (const auto& warning : operator_view_->restore_history(*state_store_, unix_now)) {
        spdlog::warn("{}", warning);
      }
    }
    spdlog::info("learned state kept under {} (saved every {} s and at shutdown)",
                 config_.state.directory, config_.state.save_seconds);
  }

  // Which detector runs for each actuator, and how long it learns before it can raise alarms.
  for (const auto& status : worker_->status()) {
    for (const auto& actuator : config_.actuators) {
      if (actuator.name == status.name) {
        spdlog::info("{}", pipeline::detector_line(actuator, status));
      }
    }
    learning_[status.name] = status.learning;
  }

  {
    io::Event event;
    event.kind = io::EventKind::daemon_started;
    event.version = LEAKMON_VERSION;
    event.config = config_path_;
    event.pid = static_cast<long long>(::getpid());
    worker_->publish(event);
  }

  std::vector<std::string> worker_warnings;
  std::atomic<bool> worker_ready{false};
  worker_thread_ = std::thread([this, &worker_warnings, &worker_ready] {
    const std::int64_t poll_ns = config_.worker_poll_ns;
    worker_warnings = realtime::make_thread_realtime(config_.worker_priority, {}).warnings;
    worker_ready.store(true, std::memory_order_release);
    while (!stop_worker_.load(std::memory_order_acquire)) {
      if (worker_->drain(realtime::monotonic_now_ns()) == 0) {
        std::this_thread::sleep_for(std::chrono::nanoseconds(poll_ns));
      }
    }
  });
  for (auto& group : groups_) {
    Group* g = group.get();
    g->thread = std::thread([this, g] {
      g->realtime = realtime::make_thread_realtime(g->config.priority, g->config.cpus);
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
  set_ack_token(config_.metrics.ack_token);
  if (config_.metrics.port != 0) {
    endpoint_ = std::make_unique<http::HttpEndpoint>(
        config_.metrics.address, config_.metrics.port,
        [this](const http::HttpRequest& request) { return handle(request); }, http::HttpLimits{},
        &http_counters_);
    spdlog::info("metrics and control on http://{}:{}/metrics", config_.metrics.address,
                 endpoint_->port());
    operator_view_->start_sampling([this](views::ServiceSnapshot& out) { fill_snapshot(out); });
    spdlog::info("live page on http://{}:{}/ ({:.1f} MB of trend history)", config_.metrics.address,
                 endpoint_->port(), static_cast<double>(operator_view_->history_bytes()) / 1e6);
  }
  if (!config_.event_log.empty()) spdlog::info("events: {}", config_.event_log);
  if (!config_.recording.directory.empty()) {
    spdlog::info("recording raw samples under {}", config_.recording.directory);
  }
  started_ns_ = realtime::monotonic_now_ns();
  last_state_save_ns_ = started_ns_;
  last_trend_save_ns_ = started_ns_;
}

void Daemon::save_state(bool with_trend) {
  if (!state_store_ || !worker_) return;
  if (operator_view_ && with_trend) {
    try {
      operator_view_->save_history(*state_store_);
    } catch (const std::exception& e) {
      spdlog::warn("cannot save the live page's trend history: {}", e.what());
    }
  }
  for (const auto& state : worker_->export_states()) {
    try {
      state_store_->save(state);
      const std::lock_guard lock(state_saved_mutex_);
      state_saved_unix_[state.actuator] = state.saved_unix;
    } catch (const std::exception& e) {
      spdlog::error("cannot save the learned state: {}", e.what());
      io::Event event;
      event.kind = io::EventKind::state_save_failed;
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
  worker_->drain(realtime::monotonic_now_ns());  // whatever the loops pushed last
  save_state(true);
  {
    // The last event: everything the loops, the worker and the state saving had to say is
    // published before it, and the sinks are flushed after it.
    io::Event event;
    event.kind = io::EventKind::daemon_stopped;
    event.version = LEAKMON_VERSION;
    event.config = config_path_;
    event.pid = static_cast<long long>(::getpid());
    event.reason = stop_reason_;
    if (started_ns_ > 0) {
      event.uptime_s = static_cast<double>(realtime::monotonic_now_ns() - started_ns_) / 1e9;
    }
    worker_->publish(event);
  }
  worker_->flush();
  endpoint_.reset();
  attach_readings(sinks_, false);
  operator_view_.reset();
  std::uint64_t pushed = 0, drops = 0;
  for (const auto& group : groups_) {
    pushed += group->loop->counters().samples_pushed.load();
    drops += group->loop->counters().ring_drops.load();
  }
  spdlog::info("stopped: {} samples acquired, {} processed, {} dropped, {} events", pushed,
               worker_->samples_processed(), drops, worker_->events_published());
  worker_.reset();
  std::lock_guard lock(sinks_mutex_);
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
    const bool with_trend =
        now_ns - last_trend_save_ns_ >= static_cast<std::int64_t>(kTrendSaveSeconds * 1e9);
    save_state(with_trend);
    last_state_save_ns_ = now_ns;
    if (with_trend) last_trend_save_ns_ = now_ns;
  }
  // The end of each actuator's learning, once (a reload that relearns starts it again).
  for (const auto& status : worker_->status()) {
    bool& learning = learning_[status.name];
    if (learning && !status.learning) spdlog::info("{}", pipeline::learning_line(status));
    learning = status.learning;
  }
  // Overruns: at most one warning (and one event) per second for all groups.
  if (now_ns - last_overrun_warning_ns_ >= kSecond) {
    for (std::size_t i = 0; i < groups_.size(); ++i) {
      const auto& counters = groups_[i]->loop->counters();
      const std::uint64_t overruns = counters.overruns.load();
      if (overruns == reported_overruns_[i]) continue;
      io::Event event;
      event.kind = io::EventKind::overrun;
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
    if (health.status != watch.status || health.detail != watch.detail) {
      io::Event event;
      event.kind = health.status == io::DeviceStatus::ok ? io::EventKind::driver_recovered
                                                         : io::EventKind::driver_fault;
      event.channel = drivers_[i]->name();
      event.message = fmt::format("state {} -> {} (NE 107 {}){}{}", watch.detail, health.detail,
                                  io::to_string(health.status),
                                  health.last_error.empty() ? "" : ": ", health.last_error);
      worker_->publish(event);
      watch.status = health.status;
      watch.detail = health.detail;
    }
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
  io::Event event;
  try {
    // Drivers and the metrics endpoint cannot change on reload (acquisition_signature), and
    // the running daemon holds their devices and port itself: those are not probed again.
    DaemonConfig next = check_config(config_path_, Preflight{false, false});
    if (acquisition_signature(next) != acquisition_signature(config_)) {
      throw config::ConfigError(fmt::format(
          "{}: drivers, sampling groups, recording, metrics, worker, realtime or state directory "
          "changed; these "
          "need a restart "
          "(systemctl restart leakmon)",
          config_path_));
    }
    auto sinks = build_sinks(next);
    attach_readings(sinks, true);
    worker_->apply(next, raw(sinks));
    {
      std::lock_guard lock(sinks_mutex_);
      sinks_.swap(sinks);  // the old sinks go only after the worker stopped using them
    }
    config_ = std::move(next);
    set_ack_token(config_.metrics.ack_token);
    ++reloads_;
    last_reload_ok_ = true;
    event.kind = io::EventKind::config_reloaded;
    event.message = config_path_;
  } catch (const std::exception& e) {
    ++reload_failures_;
    last_reload_ok_ = false;
    event.kind = io::EventKind::config_rejected;
    event.message = config::printable(e.what(), 2000);
    spdlog::error("reload rejected, the running configuration stays: {}", event.message);
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
      stop_reason_ = signal == SIGTERM ? "signal SIGTERM" : "signal SIGINT";
      break;
    }
    if (signal == SIGHUP) reload();
    housekeeping(realtime::monotonic_now_ns());
    if (all_sources_ended()) {
      spdlog::info("every source has ended: stopping");
      stop_reason_ = "end_of_sources";
      break;
    }
    if (deadline_ns > 0 && realtime::monotonic_now_ns() >= deadline_ns) {
      spdlog::info("--duration {} s reached: stopping", duration_s);
      stop_reason_ = "duration";
      break;
    }
  }
  notifier_.stopping();
  stop();
  return 0;
}

// One route per line: the path, its method, and what serves it (http/http_router.hpp answers
// 405 with Allow for another method on a known path, 404 for the rest).
http::HttpResponse Daemon::handle(const http::HttpRequest& request) {
  if (auto answer = operator_view_->handle(request)) return *answer;  // the page and its api
  const http::HttpRoute routes[] = {
      {"/metrics", "GET", [this](const http::HttpRequest&) { return metrics(); }},
      {"/status", "GET", [this](const http::HttpRequest& r) { return status(r); }},
      {"/ack", "POST", [this](const http::HttpRequest& r) { return acknowledge(r); }},
  };
  return http::route(routes, request);
}

void Daemon::set_ack_token(const std::string& token) {
  {
    const std::lock_guard lock(ack_token_mutex_);
    ack_token_ = token;
  }
  if (operator_view_) operator_view_->set_ack_token_required(!token.empty());
}

void Daemon::fill_actuators(views::ServiceSnapshot& out) const {
  out.unix_time =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  worker_->status_into(out.actuators);
  const std::lock_guard lock(state_saved_mutex_);
  for (auto& a : out.actuators) {
    const auto saved = state_saved_unix_.find(a.name);
    a.learned_state_saved_unix =
        saved == state_saved_unix_.end() ? std::numeric_limits<double>::quiet_NaN() : saved->second;
  }
}

void Daemon::fill_snapshot(views::ServiceSnapshot& out) const {
  const std::int64_t now_ns = realtime::monotonic_now_ns();
  fill_actuators(out);
  out.version = LEAKMON_VERSION;
  out.config = config_path_;
  out.uptime_s = static_cast<double>(now_ns - started_ns_) / 1e9;
  out.reload.ok = last_reload_ok_.load();
  out.reload.reloads = reloads_.load();
  out.reload.failures = reload_failures_.load();
  out.reload.last_unix = last_reload_unix_.load();
  out.cpu_latency_request_held = cpu_latency_.held();
  out.samples_processed = worker_->samples_processed();
  out.events = worker_->events_published();
  views::summarize(worker_->decision_latency(), out.decision_latency);
  out.groups.resize(groups_.size());
  for (std::size_t i = 0; i < groups_.size(); ++i) {
    const Group& g = *groups_[i];
    views::read_group(out.groups[i], g.config.name, g.loop->counters(), g.ring->capacity(),
                      g.realtime.fifo, now_ns);
  }
  out.drivers.resize(drivers_.size());
  for (std::size_t i = 0; i < drivers_.size(); ++i) {
    out.drivers[i].name = drivers_[i]->name();
    out.drivers[i].health = drivers_[i]->health();
  }
  // Outputs' own counters (io::EventSink::metrics), sorted by name: one family per name.
  out.output_metrics.clear();
  {
    std::lock_guard lock(sinks_mutex_);
    for (const auto& sink : sinks_) {
      for (const auto& metric : sink->metrics()) {
        out.output_metrics.push_back({std::string(sink->name()), metric});
      }
    }
  }
  std::stable_sort(out.output_metrics.begin(), out.output_metrics.end(),
                   [](const auto& a, const auto& b) { return a.metric.name < b.metric.name; });
  out.http.requests = http_counters_.requests.load();
  out.http.rejected = http_counters_.rejected.load();
  out.http.deadline_closes = http_counters_.deadline_closes.load();
  out.http.open_connections = http_counters_.open_connections.load();
}

http::HttpResponse Daemon::metrics() const {
  views::ServiceSnapshot snapshot;
  fill_snapshot(snapshot);
  return {200, "text/plain; version=0.0.4; charset=utf-8", views::metrics_text(snapshot)};
}

http::HttpResponse Daemon::status(const http::HttpRequest& request) const {
  const StatusFormat format = status_format(request);
  if (format.error) return *format.error;
  views::ServiceSnapshot snapshot;
  fill_snapshot(snapshot);
  const std::string json = views::status_json(snapshot);
  if (format.text) return {200, "text/plain; charset=utf-8", views::status_text_from_json(json)};
  return {200, "application/json", json};
}

// POST /ack acknowledges every actuator; POST /ack?actuator=NAME only NAME, and with
// metrics.ack_token set only with the token. Anything else acknowledges nothing
// (daemon/routes.hpp).
http::HttpResponse Daemon::acknowledge(const http::HttpRequest& request) {
  std::string token;
  {
    const std::lock_guard lock(ack_token_mutex_);
    token = ack_token_;
  }
  if (auto refusal = ack_refusal(request, token)) return *refusal;
  const AckSelection selection = ack_selection(request);
  if (selection.error) return *selection.error;
  const std::size_t matched = worker_->acknowledge(selection.actuator);
  if (matched == 0) {
    return {404, "text/plain; charset=utf-8",
            selection.actuator.empty() ? std::string("no actuators configured\n")
                                       : fmt::format("no actuator '{}'\n", selection.actuator)};
  }
  return {200, "text/plain; charset=utf-8", fmt::format("acknowledged {} actuator(s)\n", matched)};
}

}  // namespace leakmon::daemon
