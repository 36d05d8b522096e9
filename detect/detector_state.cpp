#include "detect/detector_state.hpp"

#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>

namespace leakmon::detect {

std::string format_double(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

double parse_double(std::string_view text) {
  if (text == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (text == "inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  double value = 0.0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc{} || result.ptr != text.data() + text.size() || text.empty()) {
    throw StateError("not a number: '" + std::string(text) + "'");
  }
  return value;
}

void DetectorState::expect(std::string_view kind, int version) const {
  if (kind_ != kind) {
    throw StateError("state of detector '" + kind_ + "', not '" + std::string(kind) + "'");
  }
  if (version_ != version) {
    throw StateError("detector '" + kind_ + "' state layout " + std::to_string(version_) +
                     ", this build reads " + std::to_string(version));
  }
}

void DetectorState::put(std::string_view key, double value) {
  put(key, std::span<const double>(&value, 1));
}

void DetectorState::put(std::string_view key, std::span<const double> values) {
  for (auto& [k, v] : entries_) {
    if (k == key) {
      v.assign(values.begin(), values.end());
      return;
    }
  }
  entries_.emplace_back(std::string(key), std::vector<double>(values.begin(), values.end()));
}

const std::vector<double>* DetectorState::find(std::string_view key) const {
  for (const auto& [k, v] : entries_) {
    if (k == key) return &v;
  }
  return nullptr;
}

bool DetectorState::has(std::string_view key) const { return find(key) != nullptr; }

const std::vector<double>& DetectorState::get_list(std::string_view key) const {
  const auto* values = find(key);
  if (values == nullptr) {
    throw StateError("detector '" + kind_ + "' state has no '" + std::string(key) + "'");
  }
  return *values;
}

double DetectorState::get(std::string_view key) const {
  const auto& values = get_list(key);
  if (values.size() != 1) {
    throw StateError("detector '" + kind_ + "' state: '" + std::string(key) +
                     "' should hold one value");
  }
  return values.front();
}

std::size_t DetectorState::get_count(std::string_view key) const {
  const double value = get(key);
  if (!(value >= 0.0) || value > 9.0e15 || std::floor(value) != value) {
    throw StateError("detector '" + kind_ + "' state: '" + std::string(key) + "' is not a count");
  }
  return static_cast<std::size_t>(value);
}

void DetectorState::put_nested(std::string_view prefix, const DetectorState& member) {
  const std::string head = std::string(prefix) + ".";
  put(head + "kind:" + member.kind(), static_cast<double>(member.version()));
  for (const auto& [key, values] : member.entries_) put(head + key, values);
}

DetectorState DetectorState::get_nested(std::string_view prefix) const {
  const std::string head = std::string(prefix) + ".";
  DetectorState member;
  bool found = false;
  for (const auto& [key, values] : entries_) {
    if (key.compare(0, head.size(), head) != 0) continue;
    const std::string rest = key.substr(head.size());
    if (rest.rfind("kind:", 0) == 0) {
      member.kind_ = rest.substr(5);
      member.version_ = values.size() == 1 ? static_cast<int>(values[0]) : -1;
      found = true;
    } else {
      member.entries_.emplace_back(rest, values);
    }
  }
  if (!found) throw StateError("detector '" + kind_ + "' state has no member '" + head + "'");
  return member;
}

std::string DetectorState::text() const {
  std::string out = "kind " + kind_ + "\nversion " + std::to_string(version_) + "\n";
  for (const auto& [key, values] : entries_) {
    out += key;
    for (double v : values) {
      out += ' ';
      out += format_double(v);
    }
    out += '\n';
  }
  return out;
}

DetectorState DetectorState::parse(std::string_view text) {
  DetectorState state;
  std::size_t line_number = 0;
  bool have_kind = false, have_version = false;
  while (!text.empty()) {
    ++line_number;
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    if (line.empty()) continue;
    std::vector<std::string_view> words;
    while (!line.empty()) {
      const std::size_t space = line.find(' ');
      words.push_back(line.substr(0, space));
      line.remove_prefix(space == std::string_view::npos ? line.size() : space + 1);
    }
    const auto fail = [&](const std::string& message) {
      throw StateError("detector state line " + std::to_string(line_number) + ": " + message);
    };
    if (words.front().empty()) fail("empty key");
    if (words.front() == "kind") {
      if (words.size() != 2) fail("kind needs one name");
      state.kind_ = std::string(words[1]);
      have_kind = true;
      continue;
    }
    if (words.front() == "version") {
      if (words.size() != 2) fail("version needs one number");
      try {
        state.version_ = static_cast<int>(parse_double(words[1]));
      } catch (const StateError& e) {
        fail(e.what());
      }
      have_version = true;
      continue;
    }
    std::vector<double> values;
    values.reserve(words.size() - 1);
    for (std::size_t i = 1; i < words.size(); ++i) {
      try {
        values.push_back(parse_double(words[i]));
      } catch (const StateError& e) {
        fail(e.what());
      }
    }
    if (state.has(words.front())) fail("duplicate key '" + std::string(words.front()) + "'");
    state.entries_.emplace_back(std::string(words.front()), std::move(values));
  }
  if (!have_kind || !have_version) throw StateError("detector state without kind or version");
  return state;
}

bool DetectorState::operator==(const DetectorState& other) const {
  if (kind_ != other.kind_ || version_ != other.version_ ||
      entries_.size() != other.entries_.size()) {
    return false;
  }
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const auto& [ka, va] = entries_[i];
    const auto& [kb, vb] = other.entries_[i];
    if (ka != kb || va.size() != vb.size()) return false;
    // Bitwise (so -0 differs from 0), except that any NaN equals any NaN: a round trip keeps
    // "missing", not the payload.
    for (std::size_t j = 0; j < va.size(); ++j) {
      if (std::isnan(va[j]) && std::isnan(vb[j])) continue;
      if (std::memcmp(&va[j], &vb[j], sizeof(double)) != 0) return false;
    }
  }
  return true;
}

}  // namespace leakmon::detect

namespace leakmon::detect {

std::string state_key(std::string_view prefix, std::string_view name) {
  if (prefix.empty()) return std::string(name);
  std::string key(prefix);
  key += '.';
  key += name;
  return key;
}

}  // namespace leakmon::detect
