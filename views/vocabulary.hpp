// The one vocabulary of the views: every field the JSON views (/status, the live page's
// /api/trend, the MQTT feature messages) write about an actuator, a sampling group or a trend
// column, with its one name, unit and meaning, in one table each. A view writes fields from
// these tables and nothing else, so the same quantity has the same name and unit everywhere
// (docs/daemon.md "Vocabulary"). Names carry their unit (`_pa`, `_c`, `_us`, `_s`,
// `_lpm_per_mpa`) unless the quantity has none. `state` is the actuator's state (learning,
// monitoring, alarm) and nothing else; the ISA-18.2 state of its alarm is `alarm_state`.
//
// Renamed fields keep their old name for one release (kRenamed); /status's and /api/trend's
// writers add those aliases where the old name is free.
#pragma once

#include <algorithm>
#include <initializer_list>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include "pipeline/actuator_monitor.hpp"
#include "views/json_writer.hpp"
#include "views/snapshot.hpp"
#include "views/trend_history.hpp"

namespace leakmon::views {

// One field of a row `Row`: its name, its unit (empty: none) and how to read it.
template <typename Row>
struct Field {
  using Number = double (*)(const Row&);
  using Count = std::uint64_t (*)(const Row&);
  using Flag = bool (*)(const Row&);
  using Text = std::string_view (*)(const Row&);
  std::string_view name;
  std::string_view unit;
  std::variant<Number, Count, Flag, Text> value;
};

// Writes `field` of `row` under `key` (empty: as an element of the array `out` is in).
template <typename Row>
void write_value(JsonWriter& out, std::string_view key, const Field<Row>& field, const Row& row) {
  std::visit(
      [&](auto read) {
        const auto value = read(row);
        using Value = std::remove_const_t<decltype(value)>;
        if constexpr (std::is_same_v<Value, double>) {
          out.number(key, value);
        } else if constexpr (std::is_same_v<Value, std::uint64_t>) {
          out.integer(key, value);
        } else if constexpr (std::is_same_v<Value, bool>) {
          out.boolean(key, value);
        } else {
          out.string_or_null(key, value);  // an empty text is not known
        }
      },
      field.value);
}

// Writes one field of `row` as a member of the object `out` is in.
template <typename Row>
void write_field(JsonWriter& out, const Field<Row>& field, const Row& row) {
  write_value(out, field.name, field, row);
}

// Writes every one of `fields`.
template <typename Row>
void write_fields(JsonWriter& out, std::span<const Field<Row>> fields, const Row& row) {
  for (const auto& field : fields) write_field(out, field, row);
}

// Writes the fields named `names`, in that order. A name the table does not have is a
// programming error (std::logic_error): a view cannot invent a field.
template <typename Row>
void write_fields(JsonWriter& out, std::span<const Field<Row>> fields, const Row& row,
                  std::initializer_list<std::string_view> names) {
  for (const std::string_view name : names) {
    const auto found = std::find_if(fields.begin(), fields.end(),
                                    [&](const Field<Row>& f) { return f.name == name; });
    if (found == fields.end()) {
      throw std::logic_error("views/vocabulary: no field named " + std::string(name));
    }
    write_field(out, *found, row);
  }
}

// The actuator's state: alarm while its alarm is not normal, else learning or monitoring.
std::string_view actuator_state(const pipeline::ActuatorStatus& actuator);

// Every field of an actuator but its name and its sensors (`sensors`: sensor_fields() each).
std::span<const Field<pipeline::ActuatorStatus>> actuator_fields();
std::span<const Field<pipeline::ChannelHealth>> sensor_fields();
// Every field of a sampling group but its name.
std::span<const Field<GroupSnapshot>> group_fields();
// The live page's trend columns of an actuator and of a group (`time` first, then these).
std::span<const Field<TrendPoint>> trend_columns();
std::span<const Field<LoopPoint>> loop_trend_columns();

// One renamed field: where it was, its old name, and the name it has now.
struct Renamed {
  std::string_view
      where;  // "/status", "/api/trend", "/api/trend columns", "mqtt features", "/metrics"
  std::string_view old_name;
  std::string_view name;
};
// Every renamed field, for the documentation and the tests that keep it true.
std::span<const Renamed> renamed_fields();

// An actuator as /status and /api/trend write it: `name`, actuator_fields(), `sensors`.
void write_actuator(JsonWriter& out, const pipeline::ActuatorStatus& actuator);
// A sampling group as /status and /api/trend write it: `name`, group_fields().
void write_group(JsonWriter& out, const GroupSnapshot& group);
// A driver: name, NE 107 status, detail, last error, counters.
void write_driver(JsonWriter& out, const DriverSnapshot& driver);
// The service's own members of /status and /api/trend: version, uptime_s, config, reload,
// samples_processed, events, decision_latency_p99_us.
void write_service(JsonWriter& out, const ServiceSnapshot& snapshot);

}  // namespace leakmon::views
