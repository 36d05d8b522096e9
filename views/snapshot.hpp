// The service's state as every view formats it: /metrics, /status (and `leakmon status`), the
// live page's /api/trend and the MQTT outputs' feature messages. The service (daemon/) fills one
// in place when a view needs it (a scrape, a status request, the page's sampler every interval,
// an output's feature tick); the views read nothing else, so none of them includes the service.
// Plain values, per actuator (pipeline::ActuatorStatus) and global.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "io/driver.hpp"
#include "io/event.hpp"
#include "pipeline/actuator_monitor.hpp"
#include "realtime/acquisition_loop.hpp"
#include "realtime/latency_histogram.hpp"

namespace leakmon::views {

// The upper bounds [s] of the latency histograms' Prometheus buckets.
inline constexpr std::array<double, 11> kLatencyBucketsSeconds = {
    10e-6, 20e-6, 50e-6, 100e-6, 200e-6, 500e-6, 1e-3, 2e-3, 5e-3, 10e-3, 20e-3};

// A latency histogram (realtime/latency_histogram.hpp) as far as the views show it.
struct LatencySummary {
  std::uint64_t count = 0;
  std::int64_t sum_ns = 0;
  std::int64_t max_ns = 0;
  std::int64_t p99_ns = 0;
  // Recordings below each bound of kLatencyBucketsSeconds (bin resolution, 1 us).
  std::array<std::uint64_t, kLatencyBucketsSeconds.size()> below{};

  double mean_us() const;  // NaN without a recording
  double max_us() const;   // NaN without a recording
  double p99_us() const;   // NaN without a recording
};

// Reads `histogram` into `out` (allocates nothing).
void summarize(const realtime::LatencyHistogram& histogram, LatencySummary& out);

// One sampling group's acquisition loop and ring.
struct GroupSnapshot {
  std::string name;
  bool realtime = false;  // SCHED_FIFO was granted
  bool ended = false;     // a finite source (replay) ran out
  std::uint64_t cycles = 0, overruns = 0, missed_cycles = 0, ring_drops = 0;
  std::uint64_t ring_high_water = 0, ring_capacity = 0;
  double last_cycle_age_s = std::numeric_limits<double>::quiet_NaN();  // NaN before a cycle
  LatencySummary wakeup_latency;
};

// A group's loop counters at monotonic time `now_ns` into `out`, without allocating (the name
// is assigned in place: the same name reuses its storage).
void read_group(GroupSnapshot& out, const std::string& name, const realtime::LoopCounters& counters,
                std::size_t ring_capacity, bool realtime, std::int64_t now_ns);

struct DriverSnapshot {
  std::string name;
  io::DriverHealth health;
};

// An output's own number (io::EventSink::metrics) and the output it belongs to.
struct OutputMetric {
  std::string output;
  io::SinkMetric metric;
};

struct HttpCounts {
  std::uint64_t requests = 0;
  std::uint64_t rejected = 0;
  std::uint64_t deadline_closes = 0;
  std::int64_t open_connections = 0;
};

struct ReloadStatus {
  bool ok = true;  // the last reload (or the start) succeeded
  std::uint64_t reloads = 0;
  std::uint64_t failures = 0;
  std::int64_t last_unix = 0;  // wall time of the last attempt [s], 0 before one
};

struct ServiceSnapshot {
  double unix_time = std::numeric_limits<double>::quiet_NaN();  // wall time of the fill [s]
  std::string version;
  std::string config;  // the configuration file
  double uptime_s = std::numeric_limits<double>::quiet_NaN();
  ReloadStatus reload;
  bool cpu_latency_request_held = false;
  std::uint64_t samples_processed = 0;
  std::uint64_t events = 0;
  LatencySummary decision_latency;  // sample acquired -> decision and events
  std::vector<pipeline::ActuatorStatus> actuators;
  std::vector<GroupSnapshot> groups;
  std::vector<DriverSnapshot> drivers;
  std::vector<OutputMetric> output_metrics;  // sorted by metric name
  HttpCounts http;
};

}  // namespace leakmon::views
