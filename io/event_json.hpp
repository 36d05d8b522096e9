// An event as one JSON object: the line of the JSON-lines event log (FORMATS.md `leakmon
// replay` lines) and the payload of the MQTT output, so both carry the very same text.
#pragma once

#include <string>
#include <string_view>

#include "io/event.hpp"

namespace leakmon::io {

// One JSON object, no trailing newline. Fields that are NaN or empty are left out. `index` is
// in kPa (as FORMATS.md shows it); leak sizes in l/min/MPa and l/min.
std::string to_json_line(const Event& event);

// `text` as a JSON string literal appended to `out`: quotes, backslashes and every control
// character (C0, DEL, C1: ESC and CSI included) escaped, bytes that are not UTF-8 replaced by
// U+FFFD, so the result is always valid UTF-8 JSON whatever a peer or a config put in.
void append_json_string(std::string& out, std::string_view text);
std::string json_string(std::string_view text);

// `value` as a JSON number appended to `out`: the shortest text that reads back as the same
// double, and `null` for NaN and infinities (JSON has neither). The one number writer of the
// events, the outputs' messages and the daemon's JSON views; whether an unknown value is
// written as null or left out is the object's choice (JsonObject leaves it out).
void append_json_number(std::string& out, double value);

// Builds a flat JSON object: strings escaped, empty strings and non-finite numbers left out.
class JsonObject {
 public:
  void string(std::string_view key, std::string_view value);
  void number(std::string_view key, double value);
  void boolean(std::string_view key, bool value);
  std::string finish() { return text_ + "}"; }

 private:
  void key(std::string_view key);
  std::string text_ = "{";
};

}  // namespace leakmon::io
