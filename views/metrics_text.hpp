// The Prometheus text exposition format (version 0.0.4) as a small writer: one HELP and TYPE
// header per metric family, samples with escaped label values, and histograms as cumulative
// `_bucket{le=...}` series with `_sum` and `_count`. It only builds text; whoever serves it
// (http/http_endpoint today) is someone else's business.
#pragma once

#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>

#include "pipeline/actuator_monitor.hpp"
#include "io/device_status.hpp"

namespace leakmon::views {

// A label value with `\`, `"` and newline escaped as the exposition format requires.
std::string escape_label_value(std::string_view text);

// A sample value: finite numbers in their shortest round-trip form, anything else "NaN".
std::string metric_number(double value);

class PrometheusText {
 public:
  // Starts a family: "# HELP name help" and "# TYPE name type" (counter, gauge, histogram).
  void family(std::string_view name, std::string_view help, std::string_view type);

  // One sample line. `labels` is the already formatted label list without braces (see label()),
  // empty for none.
  void sample(std::string_view name, std::string_view labels, std::uint64_t value);
  void sample(std::string_view name, std::string_view labels, std::int64_t value);
  void sample(std::string_view name, std::string_view labels, double value);

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
// oil temperature, sensor status, learned state age). `state_saved_unix`: by actuator, the wall
// time [s since 1970] the learned state kept in the state directory was saved (an actuator
// without an entry has no saved state and gets no age sample); `now_unix` the present wall time.
void actuator_metrics(PrometheusText& out, std::span<const pipeline::ActuatorStatus> actuators,
                      const std::map<std::string, double>& state_saved_unix, double now_unix);

}  // namespace leakmon::views
