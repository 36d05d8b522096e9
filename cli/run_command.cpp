// `leakmon run --config CONFIG.yaml`: the daemon (daemon/daemon.hpp).
#include <spdlog/spdlog.h>

#include <cstdlib>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/daemon.hpp"

namespace leakmon::cli {

void configure_daemon_logging() {
  // Under systemd, journald stamps each line itself: print plain lines.
  if (std::getenv("JOURNAL_STREAM") != nullptr) {
    spdlog::set_pattern("%l: %v");
  } else {
    spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %l: %v");
  }
}

int run_run(int argc, char** argv) {
  ArgParser args("run", "run the leak monitoring daemon");
  args.option("config", "CONFIG.yaml", "configuration file (schema: config/README.md)",
              std::nullopt, true);
  args.option("duration", "SECONDS",
              "stop cleanly after this long, as on SIGTERM (0: run until stopped)", "0");
  if (!args.parse(argc, argv)) return 0;
  const double duration_s = args.get_double("duration");
  if (!(duration_s >= 0)) throw UsageError("--duration must be 0 or a positive number of seconds");
  configure_daemon_logging();
  daemon::Daemon service(args.get("config"));
  return service.run(duration_s);
}

}  // namespace leakmon::cli
