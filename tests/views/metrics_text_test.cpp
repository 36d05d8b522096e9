// The Prometheus text writer on its own: label escaping, histogram series and the exposition
// layout (HELP, TYPE, then samples), and the per-actuator families built from ActuatorStatus
// values (leak size, oil temperature, sensor status, learned state age), without a daemon or a
// socket.
#include "views/metrics_text.hpp"

#include <gtest/gtest.h>

#include <string_view>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace leakmon::views {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(MetricsText, LabelValuesEscapeBackslashQuoteAndNewline) {
  EXPECT_EQ(escape_label_value("plain-name_1.x"), "plain-name_1.x");
  EXPECT_EQ(escape_label_value(R"(a"b)"), R"(a\"b)");
  EXPECT_EQ(escape_label_value(R"(c:\dir)"), R"(c:\\dir)");
  EXPECT_EQ(escape_label_value("two\nlines"), R"(two\nlines)");
  EXPECT_EQ(escape_label_value("\\\"\n"), R"(\\\"\n)");
  EXPECT_EQ(label("driver", "rig \"A\""), R"(driver="rig \"A\"")");
}

TEST(MetricsText, NumbersRoundTripAndNonFiniteIsNaN) {
  EXPECT_EQ(metric_number(0.1), "0.1");
  EXPECT_EQ(metric_number(1234.5), "1234.5");
  EXPECT_EQ(metric_number(std::numeric_limits<double>::quiet_NaN()), "NaN");
  EXPECT_EQ(metric_number(std::numeric_limits<double>::infinity()), "NaN");
  const double third = 1.0 / 3.0;
  EXPECT_EQ(std::stod(metric_number(third)), third);
}

TEST(MetricsText, FamilyHeaderThenSamples) {
  PrometheusText out;
  out.family("leakmon_x_total", "things counted", "counter");
  out.sample("leakmon_x_total", "", std::uint64_t{7});
  out.sample("leakmon_x_total", label("group", "fast"), std::uint64_t{3});
  out.family("leakmon_t_seconds", "a time", "gauge");
  out.sample("leakmon_t_seconds", "", std::int64_t{-2});
  out.sample("leakmon_t_seconds", label("a", "1") + "," + label("b", "2"), 0.25);
  EXPECT_EQ(out.text(),
            "# HELP leakmon_x_total things counted\n"
            "# TYPE leakmon_x_total counter\n"
            "leakmon_x_total 7\n"
            "leakmon_x_total{group=\"fast\"} 3\n"
            "# HELP leakmon_t_seconds a time\n"
            "# TYPE leakmon_t_seconds gauge\n"
            "leakmon_t_seconds -2\n"
            "leakmon_t_seconds{a=\"1\",b=\"2\"} 0.25\n");
}

TEST(MetricsText, HistogramBucketsAreCumulativeWithInfSumAndCount) {
  PrometheusText out;
  const double bounds[] = {1e-5, 1e-3, 0.5};
  const std::uint64_t cumulative[] = {2, 5, 9};
  out.histogram("lat_seconds", label("group", "g"), bounds, cumulative, 11, 1.75);
  EXPECT_EQ(out.text(),
            "lat_seconds_bucket{group=\"g\",le=\"1e-05\"} 2\n"
            "lat_seconds_bucket{group=\"g\",le=\"0.001\"} 5\n"
            "lat_seconds_bucket{group=\"g\",le=\"0.5\"} 9\n"
            "lat_seconds_bucket{group=\"g\",le=\"+Inf\"} 11\n"
            "lat_seconds_sum{group=\"g\"} 1.75\n"
            "lat_seconds_count{group=\"g\"} 11\n");
}

TEST(MetricsText, HistogramWithoutLabelsHasOnlyLe) {
  PrometheusText out;
  const double bounds[] = {2.0};
  const std::uint64_t cumulative[] = {0};
  out.histogram("h", "", bounds, cumulative, 0, 0.0);
  const auto lines = lines_of(out.text());
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], "h_bucket{le=\"2\"} 0");
  EXPECT_EQ(lines[1], "h_bucket{le=\"+Inf\"} 0");
}

TEST(MetricsText, HistogramRejectsBoundsAndCountsOfDifferentLength) {
  PrometheusText out;
  const double bounds[] = {1.0, 2.0};
  const std::uint64_t cumulative[] = {1};
  EXPECT_THROW(out.histogram("h", "", bounds, cumulative, 1, 1.0), std::invalid_argument);
}

// Every line of a mixed exposition has the format's shape: a comment of HELP or TYPE, or
// `name{labels} value` with quoted, escaped label values; TYPE follows the HELP of its family.
// The text format's shapes, checked by hand (std::regex is avoided: GCC 12 warns inside it
// under ASan): a metric name, and `name{label="value",...} value` with only \\, \" and \n
// escaped in values.
bool is_metric_name(std::string_view name) {
  if (name.empty()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == ':';
    if (!letter && !(i > 0 && c >= '0' && c <= '9')) return false;
  }
  return true;
}

bool is_sample_line(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && line[i] != '{' && line[i] != ' ') ++i;
  if (!is_metric_name(line.substr(0, i))) return false;
  if (i < line.size() && line[i] == '{') {
    ++i;
    while (i < line.size() && line[i] != '}') {
      const std::size_t eq = line.find('=', i);
      if (eq == std::string_view::npos || !is_metric_name(line.substr(i, eq - i))) return false;
      i = eq + 1;
      if (i >= line.size() || line[i] != '"') return false;
      for (++i; i < line.size() && line[i] != '"'; ++i) {
        if (line[i] == '\n') return false;
        if (line[i] == '\\') {
          if (++i >= line.size() || (line[i] != '\\' && line[i] != '"' && line[i] != 'n')) {
            return false;
          }
        }
      }
      if (i >= line.size()) return false;
      ++i;  // closing quote
      if (i < line.size() && line[i] == ',') ++i;
    }
    if (i >= line.size()) return false;
    ++i;  // closing brace
  }
  if (i >= line.size() || line[i] != ' ') return false;
  const std::string_view value = line.substr(i + 1);
  if (value == "NaN" || value == "+Inf") return true;
  if (value.empty()) return false;
  for (const char c : value) {
    if (!((c >= '0' && c <= '9') || c == '.' || c == 'e' || c == '+' || c == '-')) return false;
  }
  return true;
}

TEST(MetricsText, ExpositionLinesHaveTheTextFormatShape) {
  PrometheusText out;
  out.family("leakmon_driver_up", "1 when ok", "gauge");
  out.sample("leakmon_driver_up", label("driver", "bus \"0\"\\x\n") + "," + label("state", "ok"),
             std::uint64_t{1});
  out.family("leakmon_lat_seconds", "latency", "histogram");
  const double bounds[] = {1e-4, 1e-3};
  const std::uint64_t cumulative[] = {1, 2};
  out.histogram("leakmon_lat_seconds", label("group", "a,b"), bounds, cumulative, 3, 0.01);
  out.sample("leakmon_score", "", std::numeric_limits<double>::quiet_NaN());

  // The checks themselves reject what the format forbids.
  EXPECT_FALSE(is_sample_line("2bad 1"));
  EXPECT_FALSE(is_sample_line("m{a=\"x\"y\"} 1"));
  EXPECT_FALSE(is_sample_line("m{a=\"x\\q\"} 1"));
  EXPECT_FALSE(is_sample_line("m 1,5"));
  EXPECT_TRUE(is_sample_line("m{a=\"x\\\"y\",b=\"\"} -1.5e-06"));
  std::string last_help;
  const auto lines = lines_of(out.text());
  ASSERT_EQ(lines.size(), 2u + 1u + 2u + 5u + 1u);
  for (const auto& line : lines) {
    if (line.rfind("# HELP ", 0) == 0) {
      const std::size_t end = line.find(' ', 7);
      ASSERT_NE(end, std::string::npos) << line;
      last_help = line.substr(7, end - 7);
      EXPECT_TRUE(is_metric_name(last_help)) << line;
    } else if (line.rfind("# TYPE ", 0) == 0) {
      const std::size_t end = line.find(' ', 7);
      ASSERT_NE(end, std::string::npos) << line;
      EXPECT_EQ(line.substr(7, end - 7), last_help) << line;
      const std::string kind = line.substr(end + 1);
      EXPECT_TRUE(kind == "counter" || kind == "gauge" || kind == "histogram") << line;
    } else {
      EXPECT_TRUE(is_sample_line(line)) << line;
    }
  }
}

// The sample line of `name{labels}` in `text` without its value; "" when there is none.
std::string value_of(const std::string& text, const std::string& series) {
  for (const auto& line : lines_of(text)) {
    if (line.size() > series.size() && line.compare(0, series.size(), series) == 0 &&
        line[series.size()] == ' ') {
      return line.substr(series.size() + 1);
    }
  }
  return "";
}

std::size_t lines_starting(const std::string& text, std::string_view prefix) {
  std::size_t n = 0;
  for (const auto& line : lines_of(text)) n += line.rfind(prefix, 0) == 0 ? 1 : 0;
  return n;
}

TEST(MetricsText, StateSetHasOneSeriesPerNe107CategoryWithOnlyTheCurrentOneSet) {
  PrometheusText out;
  state_set(out, "s", label("driver", "bus"), io::DeviceStatus::out_of_specification);
  EXPECT_EQ(out.text(),
            "s{driver=\"bus\",status=\"ok\"} 0\n"
            "s{driver=\"bus\",status=\"failure\"} 0\n"
            "s{driver=\"bus\",status=\"function_check\"} 0\n"
            "s{driver=\"bus\",status=\"out_of_specification\"} 1\n"
            "s{driver=\"bus\",status=\"maintenance_required\"} 0\n");
  PrometheusText bare;
  state_set(bare, "s", "", io::DeviceStatus::ok);
  EXPECT_EQ(lines_of(bare.text()).front(), "s{status=\"ok\"} 1");
}

pipeline::ActuatorStatus leaking_actuator() {
  pipeline::ActuatorStatus a;
  a.name = "lift";
  a.alarm = "internal_leakage";
  a.detector = "default";
  a.state = pipeline::AlarmState::active_unacknowledged;
  a.learning = false;
  a.index_p1 = 1500.0;
  a.index_p2 = 1250.0;
  a.score = 7.5;
  // 0.15 l/min/MPa = 0.15 / 60000 m^3/s per 1e6 Pa; the half-width 0.02 l/min/MPa.
  a.leak_coefficient = 0.15 / 60000.0 / 1e6;
  a.leak_coefficient_ci = 0.02 / 60000.0 / 1e6;
  a.oil_temperature = 41.5;
  a.channels = {{"p1", io::DeviceStatus::ok, detect::SensorFault::none, 0},
                {"p2", io::DeviceStatus::failure, detect::SensorFault::none, 3}};
  return a;
}

TEST(MetricsText, ActuatorFamiliesCarryLeakSizeTemperatureSensorStatusAndStateAge) {
  pipeline::ActuatorStatus
      fresh;  // a second actuator that has no estimate, temperature or saved state
  fresh.name = "clamp";
  fresh.alarm = "internal_leakage";
  fresh.detector = "default";
  fresh.channels = {{"p1", io::DeviceStatus::function_check, detect::SensorFault::none, 0}};
  fresh.repeated_samples = 250;  // a device updating at half the sampling rate
  fresh.learning_seconds_left = 37.5;
  fresh.mode_visibility = 1.6;  // learned on a rig whose hydraulic mode did not show
  fresh.detection_blind = true;
  // Judging: `lift` judges (a quarter of its time so far), `clamp` has been in a sine block.
  fresh.judged = false;
  fresh.not_judged_reason = detect::NotJudgedReason::in_motion;
  fresh.decided_seconds = 300.0;
  std::vector<pipeline::ActuatorStatus> actuators = {leaking_actuator(), fresh};
  actuators[0].learned_state_saved_unix = 1000.0;
  actuators[0].judged = true;
  actuators[0].not_judged_reason = detect::NotJudgedReason::none;
  actuators[0].judged_seconds = 30.0;
  actuators[0].decided_seconds = 120.0;
  PrometheusText out;
  actuator_metrics(out, actuators, 1042.5);
  const std::string text = out.text();

  EXPECT_NEAR(std::stod(value_of(text, "leakmon_leak_lpm_per_mpa{actuator=\"lift\"}")), 0.15,
              1e-12);
  EXPECT_NEAR(std::stod(value_of(text, "leakmon_leak_lpm_per_mpa_ci95{actuator=\"lift\"}")), 0.02,
              1e-12);
  EXPECT_EQ(value_of(text, "leakmon_leak_lpm_per_mpa{actuator=\"clamp\"}"), "NaN");
  EXPECT_EQ(value_of(text, "leakmon_leak_lpm_per_mpa_ci95{actuator=\"clamp\"}"), "NaN");

  EXPECT_EQ(value_of(text, "leakmon_oil_temperature_celsius{actuator=\"lift\"}"), "41.5");
  EXPECT_EQ(lines_starting(text, "leakmon_oil_temperature_celsius{"), 1u);

  EXPECT_EQ(value_of(text,
                     "leakmon_sensor_status{actuator=\"lift\",channel=\"p2\",status="
                     "\"failure\"}"),
            "1");
  EXPECT_EQ(value_of(text, "leakmon_sensor_status{actuator=\"lift\",channel=\"p2\",status=\"ok\"}"),
            "0");
  EXPECT_EQ(value_of(text,
                     "leakmon_sensor_status{actuator=\"clamp\",channel=\"p1\",status="
                     "\"function_check\"}"),
            "1");
  EXPECT_EQ(lines_starting(text, "leakmon_sensor_status{"), 3u * 5u);
  EXPECT_EQ(
      value_of(text, "leakmon_sensor_spikes_rejected_total{actuator=\"lift\",channel=\"p2\"}"),
      "3");

  // The name docs/daemon.md and config/README.md give.
  EXPECT_EQ(value_of(text, "leakmon_learning_remaining_seconds{actuator=\"clamp\"}"), "37.5");
  EXPECT_EQ(value_of(text, "leakmon_acquisition_repeated_samples{actuator=\"clamp\"}"), "250");
  EXPECT_EQ(value_of(text, "leakmon_acquisition_repeated_samples{actuator=\"lift\"}"), "0");

  EXPECT_EQ(value_of(text, "leakmon_hydraulic_mode_visibility{actuator=\"clamp\"}"), "1.6");
  // Not judged (flow balance, or still learning): no sample rather than a number.
  EXPECT_EQ(lines_starting(text, "leakmon_hydraulic_mode_visibility{"), 1u);
  EXPECT_EQ(value_of(text, "leakmon_detection_blind{actuator=\"clamp\"}"), "1");
  EXPECT_EQ(value_of(text, "leakmon_detection_blind{actuator=\"lift\"}"), "0");

  EXPECT_EQ(value_of(text, "leakmon_judged{actuator=\"lift\"}"), "1");
  EXPECT_EQ(value_of(text, "leakmon_judged{actuator=\"clamp\"}"), "0");
  EXPECT_EQ(value_of(text, "leakmon_not_judged_reason{actuator=\"clamp\",reason=\"in_motion\"}"),
            "1");
  EXPECT_EQ(value_of(text, "leakmon_not_judged_reason{actuator=\"clamp\",reason=\"learning\"}"),
            "0");
  EXPECT_EQ(value_of(text, "leakmon_not_judged_reason{actuator=\"lift\",reason=\"in_motion\"}"),
            "0");
  // Every reason but `none`, per actuator: a state set Prometheus can sum over.
  EXPECT_EQ(lines_starting(text, "leakmon_not_judged_reason{"),
            2u * (detect::kNotJudgedReasonNames.size() - 1));
  EXPECT_EQ(value_of(text, "leakmon_judged_seconds_total{actuator=\"lift\"}"), "30");
  EXPECT_EQ(value_of(text, "leakmon_decided_seconds_total{actuator=\"lift\"}"), "120");
  EXPECT_EQ(value_of(text, "leakmon_judged_seconds_total{actuator=\"clamp\"}"), "0");
  EXPECT_NE(text.find("# TYPE leakmon_judged_seconds_total counter"), std::string::npos);

  EXPECT_EQ(value_of(text, "leakmon_learned_state_age_seconds{actuator=\"lift\"}"), "42.5");
  // No saved state: no age sample (not a zero that would read as "just saved").
  EXPECT_EQ(lines_starting(text, "leakmon_learned_state_age_seconds{"), 1u);

  // The alarm's ISA-18.2 state, under its one name and, for one release, under `state`.
  EXPECT_EQ(value_of(text,
                     "leakmon_alarm_active{actuator=\"lift\",alarm=\"internal_leakage\","
                     "alarm_state=\"active_unacknowledged\",state=\"active_unacknowledged\"}"),
            "1");
  EXPECT_EQ(value_of(text, "leakmon_index_pascal{actuator=\"lift\",channel=\"p2\"}"), "1250");
  EXPECT_EQ(lines_starting(text, "leakmon_index_pascal{actuator=\"clamp\""), 1u);
}

TEST(MetricsText, ActuatorFamiliesHaveOneHeaderEachAndTheTextFormatShape) {
  std::vector<pipeline::ActuatorStatus> actuators = {leaking_actuator()};
  actuators[0].learned_state_saved_unix = 5.0;
  PrometheusText out;
  actuator_metrics(out, actuators, 4.0);  // a clock that stepped back
  const std::string text = out.text();
  EXPECT_EQ(value_of(text, "leakmon_learned_state_age_seconds{actuator=\"lift\"}"), "0");
  for (const char* family : {"leakmon_leak_lpm_per_mpa", "leakmon_leak_lpm_per_mpa_ci95",
                             "leakmon_oil_temperature_celsius", "leakmon_sensor_status",
                             "leakmon_learned_state_age_seconds"}) {
    EXPECT_EQ(lines_starting(text, std::string("# TYPE ") + family + " gauge"), 1u) << family;
    EXPECT_EQ(lines_starting(text, std::string("# HELP ") + family + " "), 1u) << family;
  }
  for (const auto& line : lines_of(text)) {
    if (line.rfind("# ", 0) != 0) {
      EXPECT_TRUE(is_sample_line(line)) << line;
    }
  }
}

}  // namespace
}  // namespace leakmon::views
