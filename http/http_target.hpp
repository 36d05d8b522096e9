// The request target of an HTTP request (`/ack?actuator=cyl%201`) split into its path and
// query, with the query's `name=value` pairs separated at `&` and percent-decoded. Pure
// functions on untrusted bytes from the network: unit-tested and fuzzed
// (fuzz/http_target_fuzz.cpp); never throws, never reads past its input.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::http {

struct QueryParam {
  std::string name;        // decoded
  std::string value;       // decoded; empty both for `name=` and for a bare `name`
  bool has_value = false;  // false for a bare `name` (no '=')
};

struct RequestTarget {
  std::string path;   // decoded, starts with '/'
  std::string query;  // after '?', exactly as received (undecoded)
  std::vector<QueryParam> params;
};

struct RequestTargetResult {
  std::optional<RequestTarget> target;
  std::string error;  // why the target is malformed (a 400), when `target` is empty
};

// `%XX` -> the byte 0xXX; in a query (`plus_is_space`) `+` is a space as in HTML forms.
// Empty when a `%` is not followed by two hex digits, or when the result holds a control
// character (below 0x20, or 0x7f): no name the daemon knows has one, and they would reach logs.
std::optional<std::string> percent_decode(std::string_view text, bool plus_is_space);

// Accepts only the origin form (`/path[?query]`, RFC 9112 3.2.1). Empty pieces between `&`
// are skipped (`a=1&&b=2`, a trailing `&`); a piece splits at its first `=`, so a value may hold
// further `=`. Fragments (`#`) never belong in a request and are an error.
RequestTargetResult parse_request_target(std::string_view target);

// The first parameter named `name` (decoded), or nullptr. The one way a handler reads the query:
// nothing decodes a query string twice.
const QueryParam* find_param(std::span<const QueryParam> params, std::string_view name);

}  // namespace leakmon::http
