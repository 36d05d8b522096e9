// What a detector has learned (and where it is in its current block), as named lists of
// doubles, so that a restart can resume instead of relearning the rig with a leak already
// open. Self-describing (the detector's name and a per-detector layout version travel with
// it) and exact: text() writes every double in its shortest round-trip form (std::to_chars),
// so parse(text()) gives back the same bits, NaN and infinities included.
//
// Every value has a name: the pieces a detector is built of (detect/ring.hpp,
// drift_reference.hpp, supply_tracker.hpp, ...) save themselves under "piece.value", and a
// list of records is one list per field ("piece.field"), never positions in one list, so that
// a layout can grow without breaking what reads it (legacy_state.hpp reads the layouts from
// before that).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace leakmon::detect {

// A state that does not fit the detector importing it (other kind, other layout version,
// missing key, wrong length) or text that does not parse.
class StateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DetectorState {
 public:
  DetectorState() = default;
  DetectorState(std::string kind, int version) : kind_(std::move(kind)), version_(version) {}

  const std::string& kind() const { return kind_; }
  int version() const { return version_; }
  // Throws StateError unless this state is `kind` at layout `version`.
  void expect(std::string_view kind, int version) const;

  void put(std::string_view key, double value);
  void put(std::string_view key, std::span<const double> values);
  void put_count(std::string_view key, std::size_t value) { put(key, static_cast<double>(value)); }
  // Throw StateError when the key is missing or has another length.
  double get(std::string_view key) const;
  std::size_t get_count(std::string_view key) const;
  const std::vector<double>& get_list(std::string_view key) const;
  bool has(std::string_view key) const;

  // A member detector's state under "prefix.", for composite detectors.
  void put_nested(std::string_view prefix, const DetectorState& member);
  DetectorState get_nested(std::string_view prefix) const;

  // One line per entry: `kind NAME`, `version N`, then `KEY V1 V2 ...`. Keys hold no spaces.
  std::string text() const;
  // Inverse of text(); throws StateError naming the line on malformed input.
  static DetectorState parse(std::string_view text);

  const std::vector<std::pair<std::string, std::vector<double>>>& entries() const {
    return entries_;
  }
  bool operator==(const DetectorState& other) const;

 private:
  const std::vector<double>* find(std::string_view key) const;

  std::string kind_;
  int version_ = 0;
  std::vector<std::pair<std::string, std::vector<double>>> entries_;
};

// Exact text form of one double (shortest round trip; "nan", "inf", "-inf").
std::string format_double(double value);
// Throws StateError on anything but a whole number written by format_double().
double parse_double(std::string_view text);

// "prefix.name" (just "name" with an empty prefix): a piece's key inside a detector's state.
std::string state_key(std::string_view prefix, std::string_view name);

// One field of a record type T that is saved as a list per field: its name, and how it becomes
// a double and back (set() throws StateError on a value the field cannot hold).
template <class T>
struct RecordField {
  std::string_view name;
  double (*get)(const T&);
  void (*set)(T&, double);
};

namespace state_detail {
template <class M>
struct MemberOf;
template <class T, class V>
struct MemberOf<V T::*> {
  using Record = T;
  using Value = V;
};
}  // namespace state_detail

// The field for a double, bool or count member: record_field<&Hold::level>("level"). Record:
// the type saved, when the member is one of its base's.
template <auto Member, class Record = typename state_detail::MemberOf<decltype(Member)>::Record>
constexpr auto record_field(std::string_view name) {
  using Value = typename state_detail::MemberOf<decltype(Member)>::Value;
  if constexpr (std::is_same_v<Value, double>) {
    return RecordField<Record>{name, [](const Record& r) { return r.*Member; },
                               [](Record& r, double v) { r.*Member = v; }};
  } else if constexpr (std::is_same_v<Value, bool>) {
    return RecordField<Record>{name, [](const Record& r) { return r.*Member ? 1.0 : 0.0; },
                               [](Record& r, double v) { r.*Member = v != 0.0; }};
  } else {
    static_assert(std::is_same_v<Value, std::size_t>, "a double, bool or count member");
    return RecordField<Record>{name, [](const Record& r) { return static_cast<double>(r.*Member); },
                               [](Record& r, double v) {
                                 if (!(v >= 0.0) || v > 9.0e15 || std::floor(v) != v) {
                                   throw StateError("a count that is not one");
                                 }
                                 r.*Member = static_cast<std::size_t>(v);
                               }};
  }
}

// Records as one list per field, "prefix.field".
template <class T, std::size_t N>
void put_records(DetectorState& state, std::string_view prefix, std::span<const T> records,
                 const std::array<RecordField<T>, N>& fields) {
  std::vector<double> column(records.size());
  for (const auto& field : fields) {
    for (std::size_t i = 0; i < records.size(); ++i) column[i] = field.get(records[i]);
    state.put(state_key(prefix, field.name), column);
  }
}

// How many records put_records() saved under `prefix`; StateError when the lists differ in length.
template <class T, std::size_t N>
std::size_t record_count(const DetectorState& state, std::string_view prefix,
                         const std::array<RecordField<T>, N>& fields) {
  static_assert(N > 0);
  const std::size_t n = state.get_list(state_key(prefix, fields[0].name)).size();
  for (const auto& field : fields) {
    if (state.get_list(state_key(prefix, field.name)).size() != n) {
      throw StateError("'" + state_key(prefix, field.name) + "' differs in length from '" +
                       state_key(prefix, fields[0].name) + "'");
    }
  }
  return n;
}

// Fills `records` (record_count() of them) from what put_records() saved.
template <class T, std::size_t N>
void get_records(const DetectorState& state, std::string_view prefix,
                 const std::array<RecordField<T>, N>& fields, std::span<T> records) {
  if (record_count(state, prefix, fields) != records.size()) {
    throw StateError("'" + std::string(prefix) + "' holds another number of records");
  }
  for (const auto& field : fields) {
    const auto& column = state.get_list(state_key(prefix, field.name));
    for (std::size_t i = 0; i < records.size(); ++i) field.set(records[i], column[i]);
  }
}

}  // namespace leakmon::detect
