#include "views/json_writer.hpp"

#include <fmt/format.h>

#include <cmath>
#include <iterator>
#include <stdexcept>

#include "io/event_json.hpp"

namespace leakmon::views {

void JsonWriter::member(std::string_view key) {
  const bool spaced = style_ == Style::message;
  if (depth_ > 0) {
    if (has_members_[depth_ - 1]) out_ += spaced ? ", " : ",";
    has_members_[depth_ - 1] = true;
  }
  if (!key.empty()) {
    io::append_json_string(out_, key);
    out_ += spaced ? ": " : ":";
  }
}

void JsonWriter::open(char bracket, std::string_view key) {
  if (depth_ == kMaxDepth) throw std::logic_error("JsonWriter: nested deeper than kMaxDepth");
  member(key);
  out_ += bracket;
  has_members_[depth_++] = false;
}

void JsonWriter::close(char bracket) {
  if (depth_ == 0) throw std::logic_error("JsonWriter: closing what was not opened");
  --depth_;
  out_ += bracket;
}

void JsonWriter::begin_object(std::string_view key) { open('{', key); }
void JsonWriter::end_object() { close('}'); }
void JsonWriter::begin_array(std::string_view key) { open('[', key); }
void JsonWriter::end_array() { close(']'); }

void JsonWriter::string(std::string_view key, std::string_view value) {
  member(key);
  io::append_json_string(out_, value);
}

void JsonWriter::string_or_null(std::string_view key, std::string_view value) {
  if (value.empty()) {
    if (style_ == Style::document) null(key);
  } else {
    string(key, value);
  }
}

void JsonWriter::number(std::string_view key, double value) {
  if (!std::isfinite(value) && style_ == Style::message) return;
  member(key);
  io::append_json_number(out_, value);
}

void JsonWriter::integer(std::string_view key, std::uint64_t value) {
  member(key);
  fmt::format_to(std::back_inserter(out_), "{}", value);
}

void JsonWriter::integer(std::string_view key, std::int64_t value) {
  member(key);
  fmt::format_to(std::back_inserter(out_), "{}", value);
}

void JsonWriter::boolean(std::string_view key, bool value) {
  member(key);
  out_ += value ? "true" : "false";
}

void JsonWriter::null(std::string_view key) {
  member(key);
  out_ += "null";
}

}  // namespace leakmon::views
