// `leakmon run`: the service. Builds the pipeline from the configuration (drivers -> one
// acquisition loop thread and ring per sampling group -> worker thread -> sinks), serves
// metrics and control on 127.0.0.1, talks sd_notify, and handles signals on the main thread:
// SIGHUP reloads (an invalid configuration keeps the running one), SIGTERM/SIGINT stop cleanly
// (acquisition stops, the rings drain, events and captures are flushed). When every source is
// finite (replay without loop) and has ended, the daemon drains and exits as if stopped.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon/config.hpp"
#include "daemon/service_notifier.hpp"
#include "http/http_endpoint.hpp"
#include "io/driver.hpp"
#include "io/event.hpp"
#include "pipeline/state_store.hpp"
#include "pipeline/worker.hpp"
#include "realtime/acquisition_loop.hpp"
#include "realtime/cpu_latency_request.hpp"
#include "views/operator_view.hpp"
#include "views/snapshot.hpp"

namespace leakmon::daemon {

class Daemon {
 public:
  explicit Daemon(std::string config_path);
  ~Daemon();
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Runs until SIGTERM/SIGINT, the end of every finite source, or `duration_s` seconds (when
  // positive), whichever comes first; each ends in the same clean stop. Returns the exit code.
  // Throws config::ConfigError / io::DriverError when the configuration cannot start.
  int run(double duration_s = 0);

  // The service's state as every view formats it (views/snapshot.hpp): into `out` in place, so
  // that the live page's sampler refills a warm snapshot. Any thread; the worker's mutex is taken
  // for the actuators, as it is for everything the worker shares.
  void fill_snapshot(views::ServiceSnapshot& out) const;
  // Its wall time and actuators only: what an output's feature message reads, from the output's
  // own thread (no driver, output or HTTP counter is asked).
  void fill_actuators(views::ServiceSnapshot& out) const;

 private:
  struct Group {
    pipeline::GroupConfig config;
    std::vector<io::Driver*> drivers;
    std::unique_ptr<realtime::SpscRing<realtime::Sample>> ring;
    std::unique_ptr<realtime::AcquisitionLoop> loop;
    std::thread thread;
    realtime::RealtimeReport realtime;
    std::atomic<bool> realtime_ready{false};
  };
  // The driver health last reported in an event (main thread only).
  struct DriverWatch {
    io::DeviceStatus status = io::DeviceStatus::ok;
    std::string detail = "ok";
  };

  void start();
  void stop();
  std::vector<std::unique_ptr<io::EventSink>> build_sinks(const DaemonConfig& config) const;
  static std::vector<io::EventSink*> raw(const std::vector<std::unique_ptr<io::EventSink>>& sinks);
  // Outputs that publish live values (e.g. MQTT features) sample the worker's status snapshot
  // from their own threads; detached (empty source) before the worker goes.
  void attach_readings(const std::vector<std::unique_ptr<io::EventSink>>& sinks, bool attach) const;
  void reload();
  void housekeeping(std::int64_t now_ns);
  // Writes every actuator's learned state to the state directory (main thread; the worker is
  // locked only for the snapshot, the files are written outside it).
  // The learned state; the page's trend too when `with_trend` (it is megabytes: written every
  // kTrendSaveSeconds and at shutdown, not with every state save).
  void save_state(bool with_trend);
  bool making_progress(std::int64_t now_ns);
  bool all_sources_ended() const;
  http::HttpResponse handle(const http::HttpRequest& request);
  http::HttpResponse acknowledge(const http::HttpRequest& request);
  // metrics.ack_token, which /ack asks for: set at start and by a reload (main thread), read by
  // the HTTP threads.
  void set_ack_token(const std::string& token);
  http::HttpResponse status(const http::HttpRequest& request) const;
  http::HttpResponse metrics() const;

  std::string config_path_;
  DaemonConfig config_;
  std::vector<std::unique_ptr<io::Driver>> drivers_;
  std::vector<std::unique_ptr<Group>> groups_;
  std::vector<std::unique_ptr<io::EventSink>> sinks_;
  mutable std::mutex sinks_mutex_;  // a reload swaps sinks_ while /metrics reads them
  std::unique_ptr<pipeline::Worker> worker_;
  std::thread worker_thread_;
  std::unique_ptr<views::OperatorView> operator_view_;  // the live page; null without an endpoint
  http::HttpCounters http_counters_;  // before endpoint_: the endpoint counts into it
  std::unique_ptr<http::HttpEndpoint> endpoint_;
  std::unique_ptr<pipeline::StateStore> state_store_;  // null when state.directory is empty
  std::int64_t last_state_save_ns_ = 0;
  std::int64_t last_trend_save_ns_ = 0;
  static constexpr double kTrendSaveSeconds = 600.0;
  mutable std::mutex state_saved_mutex_;  // the main thread saves, the metrics thread reads
  std::map<std::string, double> state_saved_unix_;  // by actuator, when its state was saved
  mutable std::mutex ack_token_mutex_;
  std::string ack_token_;
  realtime::CpuLatencyRequest cpu_latency_;
  ServiceNotifier notifier_;
  std::atomic<bool> stop_acquisition_{false};
  std::atomic<bool> stop_worker_{false};

  // Housekeeping state (main thread only).
  std::vector<std::uint64_t> reported_overruns_;
  // Actuators whose detector was still learning at the last look, to log when learning ends.
  std::map<std::string, bool> learning_;
  std::vector<DriverWatch> driver_watch_;
  std::int64_t last_overrun_warning_ns_ = 0;
  std::int64_t last_watchdog_ns_ = 0;
  std::uint64_t last_processed_ = 0;
  std::int64_t started_ns_ = 0;
  // Why the daemon stops, for the daemon_stopped event: set where the main loop ends; an
  // exception that unwinds through run() leaves "error".
  std::string stop_reason_ = "error";

  // Read by the metrics thread.
  std::atomic<std::uint64_t> reloads_{0};
  std::atomic<std::uint64_t> reload_failures_{0};
  std::atomic<bool> last_reload_ok_{true};
  std::atomic<std::int64_t> last_reload_unix_{0};
};

}  // namespace leakmon::daemon
