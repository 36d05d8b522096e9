// `leakmon SUBCOMMAND [options]`: one binary, one table of subcommands.
#include <fmt/format.h>

#include <cstdio>
#include <exception>
#include <string_view>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"

namespace {

struct Subcommand {
  std::string_view name;
  std::string_view summary;
  int (*run)(int argc, char** argv);
};

constexpr Subcommand kSubcommands[] = {
    {"run", "run the leak monitoring daemon (--config CONFIG.yaml)", leakmon::cli::run_run},
    {"replay", "feed a capture through the daemon's pipeline, write its events", leakmon::cli::run_replay},
    {"check-config", "validate a daemon configuration without running it", leakmon::cli::run_check_config},
    {"probe", "read every configured channel once, in SI units with its status", leakmon::cli::run_probe},
    {"status", "summary from the running daemon", leakmon::cli::run_status},
    {"ack", "acknowledge alarms in the running daemon", leakmon::cli::run_ack},
    {"state", "show or reset what the daemon keeps across restarts", leakmon::cli::run_state},
    {"learn", "learn the healthy rig from a known-good capture (state directory)", leakmon::cli::run_learn},
    {"features", "sliding-window wavelet index of one capture channel", leakmon::cli::run_features},
    {"sim", "simulate the test rig (presets paper-fig10/13/16, scenario YAML)", leakmon::cli::run_sim},
    {"evaluate", "Monte-Carlo error rates of the leak detectors", leakmon::cli::run_evaluate},
    {"realdata", "the index on the vtnsi real-actuator data (leak and gear-damage pairs)", leakmon::cli::run_realdata},
    {"model", "model check: where the simulation disagrees with data, and why", leakmon::cli::run_model},
};

void print_help() {
  std::fputs("usage: leakmon SUBCOMMAND [options]\n\n"
             "Watches hydraulic actuators for internal leakage (db8 level-2 detail RMS of\n"
             "chamber pressure, Goharrizi, Sepehri and Wu).\n\nsubcommands:\n",
             stdout);
  for (const auto& s : kSubcommands) fmt::print("  {:<14} {}\n", s.name, s.summary);
  std::fputs("\n`leakmon SUBCOMMAND --help` describes a subcommand's options.\n", stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    print_help();
    return 2;
  }
  std::string_view name = argv[1];
  if (name == "-h" || name == "--help" || name == "help") {
    print_help();
    return 0;
  }
  if (name == "--version") {
    fmt::print("leakmon {}\n", LEAKMON_VERSION);
    return 0;
  }
  for (const auto& s : kSubcommands) {
    if (s.name != name) continue;
    try {
      return s.run(argc - 1, argv + 1);
    } catch (const leakmon::cli::UsageError& e) {
      fmt::print(stderr, "leakmon {}: {}\n(see `leakmon {} --help`)\n", name, e.what(), name);
      return 2;
    } catch (const std::exception& e) {
      fmt::print(stderr, "leakmon {}: error: {}\n", name, e.what());
      return 1;
    }
  }
  fmt::print(stderr, "leakmon: unknown subcommand '{}' (see `leakmon --help`)\n", name);
  return 2;
}
