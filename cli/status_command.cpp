// `leakmon status` and `leakmon ack`: talk to a running daemon over its metrics endpoint.
#include <fmt/format.h>

#include <cctype>
#include <string_view>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"
#include "daemon/http_endpoint.hpp"

namespace leakmon::cli {
namespace {

void endpoint_options(ArgParser& args) {
  args.option("config", "CONFIG.yaml", "take address and port from the daemon's configuration",
              std::string("/etc/leakmon/leakmon.yaml"));
  args.option("port", "N", "metrics port (overrides --config)", std::string(""));
  args.option("address", "IP", "metrics address", std::string(""));
  args.option("token", "TOKEN", "acknowledgement token (default: metrics.ack_token of --config)",
              std::string(""));
}

// Address, port and the acknowledgement token (metrics.ack_token) of the daemon's endpoint.
daemon::MetricsConfig endpoint(const ArgParser& args) {
  daemon::MetricsConfig metrics;
  if (args.get("port").empty()) {
    metrics = daemon::load_config(args.get("config")).metrics;
    if (metrics.port == 0) {
      throw UsageError(
          fmt::format("{} disables the metrics endpoint (metrics.port: 0)", args.get("config")));
    }
  } else {
    metrics.port = static_cast<int>(args.get_int("port"));
  }
  if (!args.get("address").empty()) metrics.address = args.get("address");
  if (!args.get("token").empty()) metrics.ack_token = args.get("token");
  return metrics;
}

// %XX for everything but unreserved characters, so names and tokens survive the query string.
std::string url_encoded(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += c;
    } else {
      out += fmt::format("%{:02X}", static_cast<unsigned>(u));
    }
  }
  return out;
}

}  // namespace

int run_status(int argc, char** argv) {
  ArgParser args("status", "print a summary from the running daemon");
  endpoint_options(args);
  if (!args.parse(argc, argv)) return 0;
  const auto metrics = endpoint(args);
  const auto response = daemon::http_request(metrics.address, metrics.port, "GET", "/status");
  fmt::print("{}", response.body);
  return response.status == 200 ? 0 : 1;
}

int run_ack(int argc, char** argv) {
  ArgParser args("ack", "acknowledge alarms in the running daemon");
  endpoint_options(args);
  args.option("actuator", "NAME", "only this actuator's alarm (default: all)", std::string(""));
  if (!args.parse(argc, argv)) return 0;
  const auto metrics = endpoint(args);
  std::string target = "/ack?actuator=" + url_encoded(args.get("actuator"));
  if (!metrics.ack_token.empty()) target += "&token=" + url_encoded(metrics.ack_token);
  const auto response = daemon::http_request(metrics.address, metrics.port, "POST", target);
  fmt::print("{}", response.body);
  return response.status == 200 ? 0 : 1;
}

}  // namespace leakmon::cli
