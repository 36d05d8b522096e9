#include "daemon/routes.hpp"

#include <fmt/format.h>

#include "http/http_target.hpp"

namespace leakmon::daemon {
namespace {

http::HttpResponse error(int status, std::string body) {
  return {status, "text/plain; charset=utf-8", std::move(body)};
}

}  // namespace

AckSelection ack_selection(const http::HttpRequest& request) {
  AckSelection selection;
  bool seen = false;
  bool token_seen = false;
  for (const auto& param : request.params) {
    // The acknowledgement token is checked by ack_refusal(); here it is only allowed once.
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

bool same_token(std::string_view given, std::string_view expected) {
  unsigned difference = given.size() == expected.size() ? 0u : 1u;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const char g = i < given.size() ? given[i] : '\0';
    difference |= static_cast<unsigned>(static_cast<unsigned char>(g) ^
                                        static_cast<unsigned char>(expected[i]));
  }
  return difference == 0;
}

std::optional<http::HttpResponse> ack_refusal(const http::HttpRequest& request,
                                              std::string_view token) {
  if (token.empty()) return std::nullopt;
  constexpr std::string_view kBearer = "Bearer ";
  const std::string_view authorization = request.authorization;
  if (authorization.substr(0, kBearer.size()) == kBearer &&
      same_token(authorization.substr(kBearer.size()), token)) {
    return std::nullopt;
  }
  const http::QueryParam* given = http::find_param(request.params, "token");
  if (given != nullptr && same_token(given->value, token)) return std::nullopt;
  return error(401,
               "acknowledging needs the token of metrics.ack_token: POST "
               "/ack?actuator=NAME&token=TOKEN\n");
}

StatusFormat status_format(const http::HttpRequest& request) {
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

}  // namespace leakmon::daemon
