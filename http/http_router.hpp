// Routing and parameter checks for the daemon's HTTP endpoint, free of the transport and of the
// daemon, so that they are unit-tested on their own (tests/http/http_target_test.cpp).
#pragma once

#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "http/http_endpoint.hpp"

namespace leakmon::http {

struct HttpRoute {
  std::string_view path;
  std::string_view method;  // a GET route answers HEAD too (the transport drops the body)
  std::function<HttpResponse(const HttpRequest&)> serve;
};

// The route for the request's path and method; a known path with another method is a 405
// naming the allowed ones (Allow header), an unknown path a 404 listing the paths.
HttpResponse route(std::span<const HttpRoute> routes, const HttpRequest& request);

// POST /ack: no parameters acknowledges every actuator; otherwise exactly one `actuator=NAME`
// with a non-empty NAME. Anything else (unknown, repeated or valueless parameters) is an error
// response, and nothing is acknowledged.
struct AckSelection {
  std::string actuator;  // empty: all
  std::optional<HttpResponse> error;
};
AckSelection ack_selection(const HttpRequest& request);

// GET /status: JSON unless `format=text` or an Accept header that prefers text/plain; any other
// parameter or format is an error response.
struct StatusFormat {
  bool text = false;
  std::optional<HttpResponse> error;
};
StatusFormat status_format(const HttpRequest& request);

}  // namespace leakmon::http
