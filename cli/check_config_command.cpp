// `leakmon check-config CONFIG.yaml`: the pre-flight `leakmon run` itself performs before it
// acquires anything (daemon::check_config), so that systemd's ExecStartPre and the start agree.
#include <fmt/format.h>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"

namespace leakmon::cli {

int run_check_config(int argc, char** argv) {
  ArgParser args("check-config",
                 "validate a daemon configuration as `leakmon run` does before it starts: "
                 "the file, addresses, paths, the metrics port and the devices; and whether "
                 "its network peers answer");
  args.positional("config", "CONFIG.yaml");
  args.flag("no-probe",
            "check the file and its paths only: leave out this machine's devices (CAN "
            "interfaces, serial ports), whether the metrics port is free and whether the "
            "network peers answer, e.g. for a configuration written for another machine");
  args.flag("no-peers",
            "do not connect to network peers (Modbus TCP devices, MQTT brokers), as `leakmon "
            "run` does not need them at start (the service's ExecStartPre)");
  if (!args.parse(argc, argv)) return 0;
  const std::string path = args.get("config");
  daemon::Preflight preflight;
  preflight.peers = !args.flag_set("no-peers");
  if (args.flag_set("no-probe")) preflight = daemon::Preflight{false, false, false};
  try {
    const auto config = daemon::check_config(path, preflight);
    for (const auto& warning : config.warnings) fmt::print(stderr, "warning: {}\n", warning);
    fmt::print("{}: ok ({} driver(s), {} sampling group(s), {} actuator(s){}{})\n", path,
               config.drivers.size(), config.groups.size(), config.actuators.size(),
               preflight.devices ? "" : "; devices and port not probed",
               preflight.peers || !preflight.devices ? "" : "; peers not contacted");
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}\n", e.what());
    return 1;
  }
}

}  // namespace leakmon::cli
