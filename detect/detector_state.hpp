// What a detector has learned (and where it is in its current block), as named lists of
// doubles, so that a restart can resume instead of relearning the rig with a leak already
// open. Self-describing (the detector's name and a per-detector layout version travel with
// it) and exact: text() writes every double in its shortest round-trip form (std::to_chars),
// so parse(text()) gives back the same bits, NaN and infinities included.
#pragma once

#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
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

}  // namespace leakmon::detect
