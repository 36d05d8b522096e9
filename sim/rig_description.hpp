// A rig as its user describes it (MODEL.md "Other rigs", FORMATS.md "The rig's description"):
// one mapping of data-sheet values in SI units (oil viscosities in mm^2/s), every key optional,
// a missing key meaning MODEL.md's nominal value. The simulator runs it, detectors size leaks
// with it and the model check judges data against it. One table of keys (rig_keys()) serves
// the parser, the error messages, the report and the docs, so a key is named in one place.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "config/yaml_reader.hpp"
#include "sim/oil.hpp"
#include "sim/parameters.hpp"

namespace leakmon::sim {

// One key of the description: its name in YAML, the MODEL.md symbol it sets, its unit and the
// physically meaningful range it is checked against (wider than MODEL.md's "typical range on
// other rigs": a rig outside those ranges is unusual, not impossible).
struct RigKey {
  std::string_view key;
  std::string_view symbol;  // MODEL.md's symbol, "" for keys that are not one parameter
  std::string_view unit;
  double lo, hi;
  std::string_view meaning;
};

// Every key `rig:` accepts, in MODEL.md's order. The valve's `valve_rated_flow` and
// `valve_rated_pressure_drop` (both or neither) give Kv = Q_rated / sqrt(dp_rated / 2), as
// `valve_coefficient` does directly; the oil is `oil_grade` or the two data-sheet viscosities.
std::span<const RigKey> rig_keys();

struct RigDescription {
  Parameters params;          // the stated values, nominal where the description is silent
  Oil oil = Oil::standard();  // the stated oil, ISO VG 46 when silent
  // The keys the description states (as written, e.g. "valve_rated_flow"), in file order.
  std::vector<std::string> stated;
  // Where it came from: "file:line:column" of the mapping; "" for the nominal rig.
  std::string source;
  // The rated total pressure drop the valve's data sheet quotes its rated flow at [Pa]:
  // stated with valve_rated_flow, otherwise 7 MPa (70 bar, the usual rating).
  double valve_rated_pressure_drop = 7e6;

  bool states(std::string_view key) const;
  // Whether the description states the value behind `symbol` (MODEL.md's symbol, e.g. "Kv" is
  // stated by valve_coefficient or by the rated flow and drop; "oil" by any oil key).
  bool states_symbol(std::string_view symbol) const;
  bool nominal() const { return stated.empty(); }

  static RigDescription paper() { return {}; }
};

// Reads a `rig:` mapping (the node is the mapping itself). Unknown keys, wrong types, values
// out of range and contradictions (rod not smaller than the bore; a valve given both ways; half
// of the rated pair) fail with config::ConfigError at file:line:column naming the key.
RigDescription read_rig(const config::ConfigNode& node);

// A file whose top-level key is `rig:` (other top-level keys are an error), as
// `leakmon model check --rig RIG.yaml` and `leakmon replay --rig RIG.yaml` take it.
RigDescription load_rig_file(const std::string& path);

// The value of `key` in the description's terms (SI, oil viscosities in mm^2/s; for the rated
// pair the rated flow at the stated drop, or at 7 MPa when only Kv is known). nullopt for an
// unknown key or an oil_grade of a custom oil.
std::optional<double> rig_value(const RigDescription& rig, std::string_view key);

// `rig` with `key` (a rig_keys() key that names a MODEL.md symbol, or valve_rated_flow at the
// stated rated drop) set to `value` and marked stated. Throws std::invalid_argument for an
// unknown key or an oil key.
RigDescription with_value(const RigDescription& rig, std::string_view key, double value);

// One line for logs, reports and `leakmon sim`: "bore 50 mm, rod 28 mm, supply 21 MPa, ..."
// with the stated keys only, or "the paper's rig (MODEL.md nominal)" when nothing is stated.
std::string describe(const RigDescription& rig);

// The description as a file `leakmon model check --rig` and `leakmon replay --rig` read: every
// key with a value of its own (MODEL.md's symbols and the oil's grade or viscosities).
std::string rig_file_text(const RigDescription& rig);

}  // namespace leakmon::sim
