// `leakmon check-config CONFIG.yaml`: validate without running.
#include <fmt/format.h>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"

namespace leakmon::cli {

int run_check_config(int argc, char** argv) {
  ArgParser args("check-config", "validate a daemon configuration without running it");
  args.positional("config", "CONFIG.yaml");
  if (!args.parse(argc, argv)) return 0;
  const std::string path = args.get("config");
  try {
    const auto config = daemon::check_config(path);
    fmt::print("{}: ok ({} driver(s), {} sampling group(s), {} actuator(s))\n", path,
               config.drivers.size(), config.groups.size(), config.actuators.size());
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  }
}

}  // namespace leakmon::cli
