// The views' JSON: objects and arrays appended to one string, with the project's one string and
// number writer (io/event_json.hpp: strings escaped to valid UTF-8 JSON; numbers in their
// shortest round-trip form). Two styles: a document (/status, /api/trend) is compact and writes
// a value that is not known (a number that is not finite, an empty text) as JSON null, never
// NaN; a message (an MQTT feature message) is spaced like the event it travels with and leaves
// such a value out, key and all, as the events do. Appends into the caller's string and keeps
// its nesting in a fixed array, so that a warm string is refilled without allocating.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace leakmon::views {

class JsonWriter {
 public:
  enum class Style { document, message };
  static constexpr std::size_t kMaxDepth = 16;

  explicit JsonWriter(std::string& out, Style style = Style::document) : out_(out), style_(style) {}

  // A key names a member of the enclosing object; an empty key makes an element of the
  // enclosing array (or the document itself).
  void begin_object(std::string_view key = {});
  void end_object();
  void begin_array(std::string_view key = {});
  void end_array();

  void string(std::string_view key, std::string_view value);
  void number(std::string_view key, double value);
  void integer(std::string_view key, std::uint64_t value);
  void integer(std::string_view key, std::int64_t value);
  void boolean(std::string_view key, bool value);
  void null(std::string_view key);
  // A text that may not be known: null (a message: left out) when empty.
  void string_or_null(std::string_view key, std::string_view value);

 private:
  void member(std::string_view key);  // separator, then `"key":` when given
  void open(char bracket, std::string_view key);
  void close(char bracket);

  std::string& out_;
  Style style_;
  std::array<bool, kMaxDepth> has_members_{};
  std::size_t depth_ = 0;
};

}  // namespace leakmon::views
