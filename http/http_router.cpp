#include "http/http_router.hpp"

#include <fmt/format.h>

#include <vector>

namespace leakmon::http {
namespace {

HttpResponse error(int status, std::string body) {
  return {status, "text/plain; charset=utf-8", std::move(body)};
}

bool method_matches(std::string_view route_method, std::string_view method) {
  return route_method == method || (route_method == "GET" && method == "HEAD");
}

}  // namespace

HttpResponse route(std::span<const HttpRoute> routes, const HttpRequest& request) {
  std::vector<std::string_view> allowed;
  for (const auto& r : routes) {
    if (r.path != request.path) continue;
    if (method_matches(r.method, request.method)) return r.serve(request);
    allowed.push_back(r.method);
    if (r.method == "GET") allowed.push_back("HEAD");
  }
  if (!allowed.empty()) {
    const std::string allow = fmt::format("{}", fmt::join(allowed, ", "));
    HttpResponse response = error(
        405, fmt::format("{} does not take {}; use {}\n", request.path, request.method, allow));
    response.headers.emplace_back("Allow", allow);
    return response;
  }
  std::vector<std::string> known;
  for (const auto& r : routes) known.push_back(fmt::format("{} {}", r.method, r.path));
  return error(404, fmt::format("no such resource; try {}\n", fmt::join(known, ", ")));
}

}  // namespace leakmon::http
