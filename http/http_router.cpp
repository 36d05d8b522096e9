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

AckSelection ack_selection(const HttpRequest& request) {
  AckSelection selection;
  bool seen = false;
  bool token_seen = false;
  for (const auto& param : request.params) {
    // The acknowledgement token (metrics.ack_token) is checked before routing
    // (views/operator_view.cpp); here it is only allowed once.
    if (param.name == "token") {
      if (token_seen) {
        selection.error = error(400, "give 'token' once\n");
        return selection;
      }
      token_seen = true;
      continue;
    }
    if (param.name != "actuator") {
      selection.error = error(
          400, fmt::format("unknown parameter '{}': use POST /ack?actuator=NAME, or POST /ack "
                           "to acknowledge every actuator\n",
                           param.name));
      return selection;
    }
    if (seen) {
      selection.error = error(400, "give 'actuator' once\n");
      return selection;
    }
    if (param.value.empty()) {
      selection.error = error(400, "'actuator' needs a name: POST /ack?actuator=NAME\n");
      return selection;
    }
    seen = true;
    selection.actuator = param.value;
  }
  return selection;
}

StatusFormat status_format(const HttpRequest& request) {
  StatusFormat format;
  // An explicit text/plain without application/json: a person's tool (curl -H, a browser
  // extension); Prometheus-style clients and scripts get JSON.
  format.text = request.accept.find("text/plain") != std::string::npos &&
                request.accept.find("application/json") == std::string::npos;
  bool seen = false;
  for (const auto& param : request.params) {
    if (param.name != "format" || seen) {
      format.error = error(400, fmt::format("unknown or repeated parameter '{}': GET /status or "
                                            "GET /status?format=text\n",
                                            param.name));
      return format;
    }
    seen = true;
    if (param.value == "text") {
      format.text = true;
    } else if (param.value == "json") {
      format.text = false;
    } else {
      format.error = error(400, fmt::format("format '{}': use json or text\n", param.value));
      return format;
    }
  }
  return format;
}

}  // namespace leakmon::http
