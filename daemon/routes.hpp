// The parameter checks of the service's own routes (GET /status, POST /ack), on the request the
// transport parsed (http/http_target.hpp: the query split and percent-decoded once, fuzzed), so
// that they are unit-tested without a socket (tests/daemon/routes_test.cpp).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "http/http_endpoint.hpp"

namespace leakmon::daemon {

// POST /ack: no parameters acknowledges every actuator; otherwise exactly one `actuator=NAME`
// with a non-empty NAME, and at most one `token`. Anything else (unknown, repeated or valueless
// parameters) is an error response, and nothing is acknowledged.
struct AckSelection {
  std::string actuator;  // empty: all
  std::optional<http::HttpResponse> error;
};
AckSelection ack_selection(const http::HttpRequest& request);

// POST /ack with metrics.ack_token set (`token` non-empty) needs it, as the query's `token`
// parameter (the page, `leakmon ack`) or as `Authorization: Bearer TOKEN`: a 401 response
// otherwise, nullopt when the request may acknowledge. Compared in constant time.
std::optional<http::HttpResponse> ack_refusal(const http::HttpRequest& request,
                                              std::string_view token);

// Constant-time comparison, so the time /ack takes does not reveal how much of a token matched.
bool same_token(std::string_view given, std::string_view expected);

// GET /status: JSON unless `format=text` or an Accept header that prefers text/plain; any other
// parameter or format is an error response.
struct StatusFormat {
  bool text = false;
  std::optional<http::HttpResponse> error;
};
StatusFormat status_format(const http::HttpRequest& request);

}  // namespace leakmon::daemon
