// Routing by path and method for an HTTP endpoint: what it serves is the caller's table, so the
// router knows nothing of the daemon (unit-tested in tests/http/http_target_test.cpp). The
// service's own parameter checks are daemon/routes.hpp.
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

}  // namespace leakmon::http
