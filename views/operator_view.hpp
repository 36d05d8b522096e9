// The operator's live page on the daemon's HTTP endpoint (FORMATS.md "Operator view and
// fleet"): `GET /` and its static assets (views/web/ and third_party/uplot/, compiled into the
// binary), `GET /api/trend?since=UNIX` (the trend history and the service's snapshot as JSON,
// in the vocabulary of /status) and `GET /api/events?after=SEQ` (the newest events).
//
// A sampler thread of normal priority has the service fill a ServiceSnapshot
// (views/snapshot.hpp) every metrics.trend_interval_s and appends it to the TrendHistory; the
// snapshot is reused, and recording a point allocates nothing. The real-time loops are never
// touched; the worker's mutex is taken for the snapshot, as a /metrics scrape does.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "http/http_endpoint.hpp"
#include "io/event.hpp"
#include "pipeline/config.hpp"
#include "pipeline/state_store.hpp"
#include "views/snapshot.hpp"
#include "views/trend_history.hpp"

namespace leakmon::views {

// The last `capacity` events as JSON lines (event_log.hpp's to_json_line), numbered from 1.
// Fed on the worker thread through event_sink(), read by the HTTP thread.
class RecentEvents {
 public:
  explicit RecentEvents(std::size_t capacity) : capacity_(capacity) {}
  void add(const io::Event& event);
  // A line of the event log as it was written (restored after a restart).
  void add_line(std::string line);
  // {"next": SEQ, "events": [{"seq": N, "event": {...}}, ...]} for the events after `after`.
  std::string json_after(std::uint64_t after) const;

 private:
  mutable std::mutex mutex_;
  std::size_t capacity_;
  std::deque<std::pair<std::uint64_t, std::string>> lines_;
  std::uint64_t next_ = 1;
};

class OperatorView {
 public:
  using SnapshotSource = std::function<void(ServiceSnapshot&)>;
  static constexpr std::size_t kRecentEvents = 100;

  // Allocates the trend history for the configuration's actuators and `groups`.
  OperatorView(const pipeline::DaemonConfig& config, const std::vector<std::string>& groups);
  ~OperatorView();
  OperatorView(const OperatorView&) = delete;
  OperatorView& operator=(const OperatorView&) = delete;

  // A sink for the worker's event path that keeps the recent events (it stays valid after the
  // view is gone).
  std::unique_ptr<io::EventSink> event_sink() const;
  // Where sample() reads from, without starting the thread (tests).
  void set_source(SnapshotSource source);
  // Starts the sampler thread; `source` fills a snapshot in place (Daemon::fill_snapshot). The
  // sampler stamps its points to the millisecond, the trend file's resolution.
  void start_sampling(SnapshotSource source);
  // One sample now (the sampler thread's step; tests call it directly). Allocates nothing beyond
  // what the source does once the snapshot is warm.
  void sample(double unix_time);
  // Whether POST /ack asks for metrics.ack_token (the page then shows a token field); a reload
  // may change it. The service checks the token.
  void set_ack_token_required(bool required);

  // The page's memory across a restart. save_history() writes every actuator's trend into
  // `store`'s directory (atomically, throws std::runtime_error naming the file);
  // restore_history() puts back the points of the last `trend_seconds` before `unix_now`, with
  // a gap where the daemon was down, and returns a warning for each file it set aside.
  void save_history(const pipeline::StateStore& store) const;
  std::vector<std::string> restore_history(const pipeline::StateStore& store, double unix_now);
  // The newest events of the event log (a JSON-lines file, possibly being appended to by
  // nobody else) into the page's recent events; lines that are not whole JSON objects are
  // skipped. Returns how many were taken.
  std::size_t restore_events(const std::string& event_log);

  // The page, its assets and its data; nullopt for everything else (the service's own routes).
  std::optional<http::HttpResponse> handle(const http::HttpRequest& request) const;

  // JSON of /api/trend: points after `since` (unix seconds) and the newest status.
  std::string trend_json(double since) const;
  std::size_t history_bytes() const;

 private:
  void run_sampler();

  double interval_s_;
  std::shared_ptr<RecentEvents> events_;
  SnapshotSource source_;
  ServiceSnapshot scratch_;  // the sampler's, filled outside the lock

  mutable std::mutex mutex_;  // guards everything below
  TrendHistory history_;
  ServiceSnapshot latest_;
  double latest_time_ = 0.0;
  bool ack_token_required_ = false;

  std::mutex stop_mutex_;
  std::condition_variable stop_signal_;
  bool stop_ = false;
  std::thread sampler_;
};

}  // namespace leakmon::views
