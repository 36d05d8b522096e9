#include "views/vocabulary.hpp"

#include "capture/units.hpp"
#include "detect/sensor_plausibility.hpp"
#include "io/device_status.hpp"
#include "pipeline/alarm.hpp"

namespace leakmon::views {
namespace {

using pipeline::ActuatorStatus;
using pipeline::ChannelHealth;
using A = Field<ActuatorStatus>;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr A kActuatorFields[] = {
    {"detector", "", +[](const ActuatorStatus& a) { return std::string_view(a.detector); }},
    {"state", "", +[](const ActuatorStatus& a) { return actuator_state(a); }},
    {"alarm", "", +[](const ActuatorStatus& a) { return std::string_view(a.alarm); }},
    {"alarm_state", "", +[](const ActuatorStatus& a) { return pipeline::to_string(a.state); }},
    {"learning", "", +[](const ActuatorStatus& a) { return a.learning; }},
    // Source seconds until the detector decides, while it learns.
    {"learning_seconds_left", "s",
     +[](const ActuatorStatus& a) { return a.learning ? a.learning_seconds_left : kNaN; }},
    {"suspended", "", +[](const ActuatorStatus& a) { return a.suspended; }},
    {"detection_blind", "", +[](const ActuatorStatus& a) { return a.detection_blind; }},
    {"mode_visibility", "", +[](const ActuatorStatus& a) { return a.mode_visibility; }},
    // Whether the newest decision could have revealed a leak; why not (null while judging);
    // the source time it stopped; the share of decided time judged since the start.
    {"judged", "", +[](const ActuatorStatus& a) { return a.judged; }},
    {"not_judged_reason", "",
     +[](const ActuatorStatus& a) {
       return a.judged ? std::string_view() : detect::to_string(a.not_judged_reason);
     }},
    {"not_judged_since", "s",
     +[](const ActuatorStatus& a) { return a.judged ? kNaN : a.not_judged_since; }},
    {"judged_share", "",
     +[](const ActuatorStatus& a) {
       return a.decided_seconds > 0.0 ? a.judged_seconds / a.decided_seconds : kNaN;
     }},
    {"t", "s", +[](const ActuatorStatus& a) { return a.t; }},
    {"index_p1_pa", "Pa", +[](const ActuatorStatus& a) { return a.index_p1; }},
    {"index_p2_pa", "Pa", +[](const ActuatorStatus& a) { return a.index_p2; }},
    {"score", "", +[](const ActuatorStatus& a) { return a.score; }},
    {"raise_threshold", "", +[](const ActuatorStatus& a) { return a.raise_threshold; }},
    {"clear_threshold", "", +[](const ActuatorStatus& a) { return a.clear_threshold; }},
    {"baseline_pa", "Pa", +[](const ActuatorStatus& a) { return a.baseline; }},
    {"leak_lpm_per_mpa", "l/min/MPa",
     +[](const ActuatorStatus& a) { return units::lpm_per_mpa(a.leak_coefficient); }},
    {"leak_lpm_per_mpa_ci95", "l/min/MPa",
     +[](const ActuatorStatus& a) { return units::lpm_per_mpa(a.leak_coefficient_ci); }},
    {"p1_pa", "Pa", +[](const ActuatorStatus& a) { return a.p1; }},
    {"p2_pa", "Pa", +[](const ActuatorStatus& a) { return a.p2; }},
    {"oil_temperature_c", "degC", +[](const ActuatorStatus& a) { return a.oil_temperature; }},
    {"decisions", "", +[](const ActuatorStatus& a) { return a.decisions; }},
    {"gap_samples", "", +[](const ActuatorStatus& a) { return a.gap_samples; }},
};

constexpr Field<ChannelHealth> kSensorFields[] = {
    {"channel", "", +[](const ChannelHealth& c) { return std::string_view(c.channel); }},
    // NAMUR NE 107 category.
    {"status", "", +[](const ChannelHealth& c) { return io::to_string(c.status); }},
    // What the plausibility check found (also while the channel recovers); null for none.
    {"fault", "",
     +[](const ChannelHealth& c) {
       return c.fault == detect::SensorFault::none ? std::string_view()
                                                   : detect::to_string(c.fault);
     }},
    {"spikes_rejected", "", +[](const ChannelHealth& c) { return c.spikes_rejected; }},
};

constexpr Field<GroupSnapshot> kGroupFields[] = {
    {"realtime", "", +[](const GroupSnapshot& g) { return g.realtime; }},
    {"ended", "", +[](const GroupSnapshot& g) { return g.ended; }},
    {"cycles", "", +[](const GroupSnapshot& g) { return g.cycles; }},
    {"overruns", "", +[](const GroupSnapshot& g) { return g.overruns; }},
    {"missed_cycles", "", +[](const GroupSnapshot& g) { return g.missed_cycles; }},
    {"ring_drops", "", +[](const GroupSnapshot& g) { return g.ring_drops; }},
    {"ring_high_water", "", +[](const GroupSnapshot& g) { return g.ring_high_water; }},
    {"ring_capacity", "", +[](const GroupSnapshot& g) { return g.ring_capacity; }},
    {"wakeup_latency_mean_us", "us",
     +[](const GroupSnapshot& g) { return g.wakeup_latency.mean_us(); }},
    {"wakeup_latency_p99_us", "us",
     +[](const GroupSnapshot& g) { return g.wakeup_latency.p99_us(); }},
    {"wakeup_latency_max_us", "us",
     +[](const GroupSnapshot& g) { return g.wakeup_latency.max_us(); }},
    {"last_cycle_age_s", "s", +[](const GroupSnapshot& g) { return g.last_cycle_age_s; }},
};

constexpr Field<TrendPoint> kTrendColumns[] = {
    {"index_p1_pa", "Pa", +[](const TrendPoint& p) { return p.index_p1; }},
    {"index_p2_pa", "Pa", +[](const TrendPoint& p) { return p.index_p2; }},
    {"score", "", +[](const TrendPoint& p) { return p.score; }},
    {"raise_threshold", "", +[](const TrendPoint& p) { return p.raise_threshold; }},
    {"leak_lpm_per_mpa", "l/min/MPa", +[](const TrendPoint& p) { return p.leak_lpm_per_mpa; }},
    {"leak_lpm_per_mpa_ci95", "l/min/MPa",
     +[](const TrendPoint& p) { return p.leak_lpm_per_mpa_ci95; }},
    {"p1_pa", "Pa", +[](const TrendPoint& p) { return p.p1; }},
    {"p2_pa", "Pa", +[](const TrendPoint& p) { return p.p2; }},
    {"oil_temperature_c", "degC", +[](const TrendPoint& p) { return p.oil_temperature; }},
    // The alarm's ISA-18.2 state as its number (pipeline/alarm.hpp AlarmState: 0 normal, 1
    // active unacknowledged, 2 active acknowledged, 3 returned unacknowledged).
    {"alarm_state_code", "", +[](const TrendPoint& p) { return static_cast<double>(p.alarm); }},
};

constexpr Field<LoopPoint> kLoopTrendColumns[] = {
    {"wakeup_latency_mean_us", "us", +[](const LoopPoint& p) { return p.latency_mean_us; }},
    {"overruns", "", +[](const LoopPoint& p) { return static_cast<double>(p.overruns); }},
};

constexpr Renamed kRenamed[] = {
    {"/status", "index_pa.p1", "index_p1_pa"},
    {"/status", "index_pa.p2", "index_p2_pa"},
    {"/status", "threshold.raise", "raise_threshold"},
    {"/status", "threshold.clear", "clear_threshold"},
    {"/status", "alarms[].name", "alarm"},
    {"/status", "alarms[].state", "alarm_state"},
    {"/status", "groups[].wakeup_latency_us.mean", "wakeup_latency_mean_us"},
    {"/status", "groups[].wakeup_latency_us.max", "wakeup_latency_max_us"},
    {"/api/trend", "index_p1", "index_p1_pa"},
    {"/api/trend", "index_p2", "index_p2_pa"},
    {"/api/trend", "p1", "p1_pa"},
    {"/api/trend", "p2", "p2_pa"},
    {"/api/trend", "oil_temperature", "oil_temperature_c"},
    {"/api/trend", "channels", "sensors"},
    {"/api/trend", "groups[].latency_mean_us", "wakeup_latency_mean_us"},
    {"/api/trend", "groups[].latency_p99_us", "wakeup_latency_p99_us"},
    {"/api/trend", "groups[].latency_max_us", "wakeup_latency_max_us"},
    {"/api/trend columns", "index_p1", "index_p1_pa"},
    {"/api/trend columns", "index_p2", "index_p2_pa"},
    {"/api/trend columns", "p1", "p1_pa"},
    {"/api/trend columns", "p2", "p2_pa"},
    {"/api/trend columns", "oil_temperature", "oil_temperature_c"},
    {"/api/trend columns", "alarm", "alarm_state_code"},
    {"/api/trend columns", "groups[].latency_mean_us", "wakeup_latency_mean_us"},
    {"mqtt features", "index", "index_p1_pa"},
    {"/metrics", "leakmon_alarm_active{state}", "leakmon_alarm_active{alarm_state}"},
    {"/metrics", "leakmon_driver_up{state}", "leakmon_driver_up{detail}"},
};

}  // namespace

std::string_view actuator_state(const ActuatorStatus& actuator) {
  if (actuator.state != pipeline::AlarmState::normal) return "alarm";
  return actuator.learning ? "learning" : "monitoring";
}

std::span<const Field<ActuatorStatus>> actuator_fields() { return kActuatorFields; }
std::span<const Field<ChannelHealth>> sensor_fields() { return kSensorFields; }
std::span<const Field<GroupSnapshot>> group_fields() { return kGroupFields; }
std::span<const Field<TrendPoint>> trend_columns() { return kTrendColumns; }
std::span<const Field<LoopPoint>> loop_trend_columns() { return kLoopTrendColumns; }
std::span<const Renamed> renamed_fields() { return kRenamed; }

void write_actuator(JsonWriter& out, const ActuatorStatus& actuator) {
  out.string("name", actuator.name);
  write_fields(out, actuator_fields(), actuator);
  out.begin_array("sensors");
  for (const auto& channel : actuator.channels) {
    out.begin_object();
    write_fields(out, sensor_fields(), channel);
    out.end_object();
  }
  out.end_array();
}

void write_group(JsonWriter& out, const GroupSnapshot& group) {
  out.string("name", group.name);
  write_fields(out, group_fields(), group);
}

void write_driver(JsonWriter& out, const DriverSnapshot& driver) {
  out.string("name", driver.name);
  out.string("status", io::to_string(driver.health.status));
  out.string("detail", driver.health.detail);
  out.string_or_null("last_error", driver.health.last_error);
  out.integer("errors", driver.health.errors);
  out.integer("reconnects", driver.health.reconnects);
  out.integer("stale_values", driver.health.stale_values);
}

void write_service(JsonWriter& out, const ServiceSnapshot& snapshot) {
  out.string("version", snapshot.version);
  out.number("uptime_s", snapshot.uptime_s);
  out.string("config", snapshot.config);
  out.begin_object("reload");
  out.boolean("ok", snapshot.reload.ok);
  out.integer("reloads", snapshot.reload.reloads);
  out.integer("failures", snapshot.reload.failures);
  out.integer("last_unix", snapshot.reload.last_unix);
  out.end_object();
  out.integer("samples_processed", snapshot.samples_processed);
  out.integer("events", snapshot.events);
  out.number("decision_latency_p99_us", snapshot.decision_latency.p99_us());
}

}  // namespace leakmon::views
