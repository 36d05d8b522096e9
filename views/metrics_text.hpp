// GET /metrics: the service's snapshot in the Prometheus text exposition format (version 0.0.4).
// PrometheusText is the small writer (one HELP and TYPE header per metric family, samples with
// escaped label values, histograms as cumulative `_bucket{le=...}` series with `_sum` and
// `_count`); every family the daemon exports is declared once, with its name, help and type, in
// metrics_text.cpp, as node_exporter's collectors declare theirs. It only builds text; serving it
// is the transport's business.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "io/device_status.hpp"
#include "pipeline/actuator_monitor.hpp"
#include "views/snapshot.hpp"

namespace leakmon::views {

// A label value with `\`, `"` and newline escaped as the exposition format requires.
std::string escape_label_value(std::string_view text);

// A sample value: finite numbers in their shortest round-trip form, anything else "NaN".
std::string metric_number(double value);

enum class MetricType { counter, gauge, histogram };
std::string_view to_string(MetricType type);

// A metric family: its name, help text and type, declared once.
struct MetricFamily {
  std::string_view name;
  std::string_view help;
  MetricType type;
};

class PrometheusText {
 public:
  // Starts a family: "# HELP name help" and "# TYPE name type".
  void family(const MetricFamily& family);
  void family(std::string_view name, std::string_view help, std::string_view type);

  // One sample line. `labels` is the already formatted label list without braces (see label()),
  // empty for none.
  void sample(std::string_view name, std::string_view labels, std::uint64_t value);
  void sample(std::string_view name, std::string_view labels, std::int64_t value);
  void sample(std::string_view name, std::string_view labels, double value);
  template <typename Value>
  void sample(const MetricFamily& family, std::string_view labels, Value value) {
    sample(family.name, labels, value);
  }

  // The series of one histogram: `upper_bounds` in increasing order with their cumulative
  // counts (`cumulative[i]` observations <= upper_bounds[i]), then le="+Inf" (= count), _sum and
  // _count.
  void histogram(std::string_view name, std::string_view labels,
                 std::span<const double> upper_bounds, std::span<const std::uint64_t> cumulative,
                 std::uint64_t count, double sum);

  const std::string& text() const { return out_; }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

// `name="value"` with the value escaped; join several with ",".
std::string label(std::string_view name, std::string_view value);

// A NAMUR NE 107 state set: one sample per category (`status` label), 1 for `current`, 0 for the
// others, so that `== 1` selects the present category and a change is a change of series value.
void state_set(PrometheusText& out, std::string_view name, std::string_view labels,
               io::DeviceStatus current);

// The per-actuator families of /metrics (index, score, alarm, leak size with its 95 % half-width,
// oil temperature, sensor status, learned state age). An actuator whose learned state was never
// saved (ActuatorStatus::learned_state_saved_unix NaN) gets no age sample; `now_unix` is the
// present wall time.
void actuator_metrics(PrometheusText& out, std::span<const pipeline::ActuatorStatus> actuators,
                      double now_unix);

// Everything /metrics answers.
std::string metrics_text(const ServiceSnapshot& snapshot);

}  // namespace leakmon::views
