// A request as the HTTP endpoint builds it from the request line (http/http_endpoint.cpp): the
// target parsed by the transport's one, fuzzed decoder. For tests of the routes and views that
// take an http::HttpRequest; header-only, so only tests that link leakmon_http include it.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <utility>

#include "http/http_endpoint.hpp"
#include "http/http_target.hpp"

namespace leakmon::test {

inline http::HttpRequest request(std::string method, std::string_view target) {
  const http::RequestTargetResult parsed = http::parse_request_target(target);
  EXPECT_TRUE(parsed.target.has_value()) << target << ": " << parsed.error;
  http::HttpRequest r;
  r.method = std::move(method);
  if (parsed.target) {
    r.path = parsed.target->path;
    r.query = parsed.target->query;
    r.params = parsed.target->params;
  }
  return r;
}

}  // namespace leakmon::test
