// `leakmon status` and `leakmon ack`: talk to a running daemon over its metrics endpoint.
#include <fmt/format.h>

#include <filesystem>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"
#include "http/http_endpoint.hpp"
#include "views/status_json.hpp"

namespace leakmon::cli {
namespace {

// Where the installed unit reads its configuration (LEAKMON_CONFIG_DIR at build time), so that
// `status` and `ack` find the service's port and token without --config.
constexpr const char* kDefaultConfig = LEAKMON_DEFAULT_CONFIG;

void endpoint_options(ArgParser& args) {
  args.option("config", "CONFIG.yaml",
              "take address, port and acknowledgement token from the daemon's configuration "
              "(when it exists, the default's does not have to: then the built-in "
              "127.0.0.1:9187)",
              std::string(kDefaultConfig));
  args.option("port", "N", "metrics port (overrides --config)", std::string(""));
  args.option("address", "IP", "metrics address", std::string(""));
  args.option("token", "TOKEN", "acknowledgement token (default: metrics.ack_token of --config)",
              std::string(""));
}

// Address, port and the acknowledgement token (metrics.ack_token) of the daemon's endpoint.
pipeline::MetricsConfig endpoint(const ArgParser& args) {
  pipeline::MetricsConfig metrics;  // the daemon's own defaults
  const std::string config = args.get("config");
  if (args.get("port").empty()) {
    // A configuration named on the command line must exist; the default one may be absent (a
    // daemon run with --config elsewhere, or on the defaults): then the built-in port applies.
    if (config != kDefaultConfig || std::filesystem::exists(config)) {
      metrics = daemon::load_config(config).metrics;
      if (metrics.port == 0) {
        throw UsageError(fmt::format("{} disables the metrics endpoint (metrics.port: 0)", config));
      }
    }
  } else {
    metrics.port = static_cast<int>(args.get_int("port"));
  }
  if (!args.get("address").empty()) metrics.address = args.get("address");
  if (!args.get("token").empty()) metrics.ack_token = args.get("token");
  return metrics;
}

}  // namespace

int run_status(int argc, char** argv) {
  ArgParser args("status", "print a summary from the running daemon");
  endpoint_options(args);
  args.flag("json", "print the daemon's JSON status as it is");
  if (!args.parse(argc, argv)) return 0;
  const auto metrics = endpoint(args);
  const auto response = http::http_request(metrics.address, metrics.port, "GET", "/status");
  if (response.status != 200 || args.flag_set("json")) {
    fmt::print("{}", response.body);
    return response.status == 200 ? 0 : 1;
  }
  fmt::print("{}", views::status_text_from_json(response.body));
  return 0;
}

int run_ack(int argc, char** argv) {
  ArgParser args("ack", "acknowledge alarms in the running daemon");
  endpoint_options(args);
  args.option("actuator", "NAME", "only this actuator's alarm (default: all)", std::string(""));
  if (!args.parse(argc, argv)) return 0;
  const auto metrics = endpoint(args);
  const std::string actuator = args.get("actuator");
  std::string query;
  if (!actuator.empty()) query = "actuator=" + http::percent_encode(actuator);
  if (!metrics.ack_token.empty()) {
    // Piece by piece: GCC 12's -O3 takes "literal" + std::string for an overlapping memcpy.
    if (!query.empty()) query += '&';
    query += "token=";
    query += http::percent_encode(metrics.ack_token);
  }
  const auto response = http::http_request(metrics.address, metrics.port, "POST",
                                           query.empty() ? "/ack" : "/ack?" + query);
  fmt::print("{}", response.body);
  return response.status == 200 ? 0 : 1;
}

}  // namespace leakmon::cli
