// A detector kind's options as one table: each row is a key with its meaning, its range and
// where it goes in the kind's options struct (whose default-constructed value holds the
// default). The factory reads a configured mapping through it, rejects keys outside it (at the
// key's file:line:column) and writes the options' reference in docs/detection.md from it, so a
// key, its range and its default are written once.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "config/yaml_reader.hpp"

namespace leakmon::detect {

// The longest time option [s].
inline constexpr double kMaxOptionSeconds = 86400.0;

template <class O>
struct Option {
  std::string_view key;
  std::string_view meaning;
  // The closed range of a number.
  double lo = 0.0, hi = 0.0;
  // A number at field(options); or, for anything else (a flag, a choice, keys read together, a
  // derived value), `read` (null: the key is read by another row), with its default and range
  // stated for the reference (an empty range_text: lo to hi).
  double& (*field)(O&) = nullptr;
  void (*read)(O&, const config::ConfigNode*, const Option&) = nullptr;
  std::string_view default_text = {}, range_text = {};
  // The default read from the options (instead of default_text).
  std::string (*default_of)(O&) = nullptr;
  // A flag (true, false) at flag(options).
  bool& (*flag)(O&) = nullptr;
};

template <class O>
Option<O> number_option(std::string_view key, double lo, double hi, std::string_view meaning,
                        double& (*field)(O&)) {
  return {key, meaning, lo, hi, field, nullptr, {}, {}, nullptr};
}

template <class O>
Option<O> other_option(std::string_view key, std::string_view default_text,
                       std::string_view range_text, std::string_view meaning,
                       void (*read)(O&, const config::ConfigNode*, const Option<O>&),
                       double lo = 0.0, double hi = 0.0, std::string (*default_of)(O&) = nullptr) {
  return {key, meaning, lo, hi, nullptr, read, default_text, range_text, default_of};
}

template <class O>
Option<O> flag_option(std::string_view key, std::string_view meaning, bool& (*flag)(O&)) {
  return {key, meaning, 0.0, 0.0, nullptr, nullptr, {}, "true, false", nullptr, flag};
}

template <class O>
std::vector<Option<O>> operator+(std::vector<Option<O>> a, const std::vector<Option<O>>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

template <class O>
std::vector<std::string> option_keys(const std::vector<Option<O>>& rows) {
  std::vector<std::string> keys;
  for (const auto& row : rows) keys.emplace_back(row.key);
  return keys;
}

// Applies every row in order to `options` from the configured mapping `node` (null: none, the
// defaults stay): a configured number is range-checked at its key.
template <class O>
void read_options(const std::vector<Option<O>>& rows, O& options, const config::ConfigNode* node) {
  for (const auto& row : rows) {
    if (row.field != nullptr) {
      double& value = row.field(options);
      if (node != nullptr) value = node->get_double(row.key, value, row.lo, row.hi);
    } else if (row.flag != nullptr) {
      bool& value = row.flag(options);
      if (node != nullptr) value = node->get_bool(row.key, value);
    } else if (row.read != nullptr) {
      row.read(options, node, row);
    }
  }
}

inline std::string option_number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

// The rows as a Markdown table: key, default, range, meaning.
template <class O>
std::string options_markdown(const std::vector<Option<O>>& rows, O defaults = O{}) {
  std::string out = "| key | default | range | meaning |\n|---|---|---|---|\n";
  for (const auto& row : rows) {
    const std::string value = row.field != nullptr ? option_number_text(row.field(defaults))
                              : row.flag != nullptr
                                  ? std::string(row.flag(defaults) ? "true" : "false")
                              : row.default_of != nullptr ? row.default_of(defaults)
                                                          : std::string(row.default_text);
    const std::string range = row.range_text.empty()
                                  ? option_number_text(row.lo) + " to " + option_number_text(row.hi)
                                  : std::string(row.range_text);
    out += "| `" + std::string(row.key) + "` | " + value + " | " + range + " | " +
           std::string(row.meaning) + " |\n";
  }
  return out;
}

}  // namespace leakmon::detect
