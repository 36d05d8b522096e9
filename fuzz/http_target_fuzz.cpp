// Fuzzes the HTTP request-target parser (http/http_target.cpp) with raw bytes as a peer would
// send them. Invariants: a parsed target's path starts with '/', no decoded name, value or path
// holds a control character, the raw query is kept exactly, and percent-encoding each decoded
// parameter and parsing again gives the same parameters (decoding loses nothing).
// fuzz-sources: http/http_target.cpp
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "http/http_target.hpp"

using namespace leakmon::http;

namespace {

bool has_control(std::string_view text) {
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) return true;
  }
  return false;
}

std::string encode(std::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte >= '0' && byte <= '9') || (byte >= 'a' && byte <= 'z') ||
        (byte >= 'A' && byte <= 'Z')) {
      out += c;
    } else {
      out += '%';
      out += kHex[byte >> 4];
      out += kHex[byte & 15];
    }
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const RequestTargetResult result = parse_request_target(text);
  if (!result.target) {
    if (result.error.empty()) __builtin_trap();
    return 0;
  }
  const RequestTarget& target = *result.target;
  if (target.path.empty() || target.path.front() != '/') __builtin_trap();
  if (has_control(target.path)) __builtin_trap();
  const auto question = text.find('?');
  if (question == std::string_view::npos ? !target.query.empty()
                                         : target.query != text.substr(question + 1)) {
    __builtin_trap();
  }
  std::string again = "/?";
  for (const auto& param : target.params) {
    if (param.name.empty() && !param.has_value) __builtin_trap();  // empty pieces are skipped
    if (has_control(param.name) || has_control(param.value)) __builtin_trap();
    if (!param.has_value && !param.value.empty()) __builtin_trap();
    again += encode(param.name);
    if (param.has_value) again += "=" + encode(param.value);
    again += "&";
  }
  const RequestTargetResult reparsed = parse_request_target(again);
  if (!reparsed.target || reparsed.target->params.size() != target.params.size()) __builtin_trap();
  for (std::size_t i = 0; i < target.params.size(); ++i) {
    const auto& a = target.params[i];
    const auto& b = reparsed.target->params[i];
    if (a.name != b.name || a.value != b.value || a.has_value != b.has_value) __builtin_trap();
  }
  return 0;
}
