// `leakmon state show|reset|learn` and `leakmon learn`: what the daemon keeps across restarts
// in its state directory (pipeline/state_store.hpp, docs/daemon.md "Restarts").
#include <fmt/chrono.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "capture/capture.hpp"
#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"
#include "detect/legacy_state.hpp"
#include "pipeline/replay.hpp"
#include "pipeline/state_store.hpp"

namespace leakmon::cli {
namespace {

std::string utc(double unix_seconds) {
  const auto t = std::chrono::system_clock::time_point(
      std::chrono::seconds(static_cast<long long>(std::floor(unix_seconds))));
  return fmt::format("{:%Y-%m-%d %H:%M:%S} UTC", t);
}

struct Target {
  std::optional<daemon::DaemonConfig> config;
  std::string directory;
};

void add_target_options(ArgParser& args) {
  args.option("config", "CONFIG.yaml",
              "daemon configuration: its state.directory and actuators (to tell whether a saved "
              "state still fits)",
              std::string(""));
  args.option("state-dir", "DIR", "state directory (default: the configuration's state.directory)",
              std::string(""));
}

Target target_of(const ArgParser& args) {
  Target target;
  if (!args.get("config").empty()) target.config = daemon::load_config(args.get("config"));
  target.directory = args.get("state-dir");
  if (target.directory.empty() && target.config) target.directory = target.config->state.directory;
  if (target.directory.empty()) {
    throw UsageError(target.config ? "the configuration keeps no state (state.directory is empty); "
                                     "give --state-dir"
                                   : "give --config or --state-dir");
  }
  return target;
}

int show(const Target& target) {
  const pipeline::StateStore store(target.directory);
  const auto listing = store.list();
  fmt::print("state directory {}: {} saved actuator state(s)\n", target.directory,
             listing.states.size());
  std::vector<std::pair<std::string, pipeline::StateFingerprint>> expected;
  if (target.config) expected = pipeline::state_fingerprints(*target.config);
  for (const auto& state : listing.states) {
    fmt::print("actuator {}: saved {}, detector {} ({}), alarm {}{}\n", state.actuator,
               utc(state.saved_unix), state.detector.kind(),
               detect::has_learned(state.detector) ? "learned" : "still learning",
               pipeline::to_string(state.alarm),
               state.alarm_condition ? " (condition active)" : "");
    for (const auto& [name, value] : state.fingerprint.parts) {
      fmt::print("  {}: {}\n", name, value);
    }
    if (!target.config) continue;
    bool found = false;
    for (const auto& [name, fingerprint] : expected) {
      if (name != state.actuator) continue;
      found = true;
      fmt::print("  {}\n", fingerprint == state.fingerprint
                               ? "fits the configuration: the daemon resumes from it"
                               : "does NOT fit the configuration (it changed): the daemon will "
                                 "set it aside and learn afresh");
    }
    if (!found) fmt::print("  no such actuator in the configuration (ignored)\n");
  }
  for (const auto& [path, error] : listing.unreadable) {
    fmt::print("{}: unreadable ({}): the daemon will learn afresh\n", path.string(), error);
  }
  if (target.config) {
    for (const auto& [name, fingerprint] : expected) {
      bool saved = false;
      for (const auto& state : listing.states) saved |= state.actuator == name;
      if (!saved) fmt::print("actuator {}: nothing saved (learns on start)\n", name);
    }
  }
  return 0;
}

int reset(const Target& target, const std::string& actuator) {
  const pipeline::StateStore store(target.directory);
  std::vector<std::string> names;
  if (!actuator.empty()) {
    names.push_back(actuator);
  } else {
    for (const auto& state : store.list().states) names.push_back(state.actuator);
    if (target.config) {
      for (const auto& a : target.config->actuators) names.push_back(a.name);
    }
  }
  std::size_t removed = 0;
  for (const auto& name : names) {
    if (store.remove(name)) {
      fmt::print("actuator {}: saved state deleted ({})\n", name, store.file_of(name).string());
      ++removed;
    }
  }
  if (removed == 0) fmt::print("nothing to delete under {}\n", target.directory);
  fmt::print(
      "a running daemon keeps what it has learned in memory and saves it again: stop it first "
      "(systemctl stop leakmon), reset, then start it\n");
  return 0;
}

int learn(const Target& target, const std::string& capture_path) {
  if (!target.config) throw UsageError("learn needs --config (the actuators to learn)");
  auto capture = std::make_shared<const capture::Capture>(capture::read_capture(capture_path));
  const auto result = pipeline::replay_capture(capture, *target.config, {});
  for (const auto& event : result.events) {
    if (event.kind == io::EventKind::alarm_raised) {
      fmt::print(stderr,
                 "warning: {} raised {} at t={:.2f} s while learning from {}: is that capture "
                 "really of a healthy rig?\n",
                 event.actuator, event.alarm, event.t, capture_path);
    }
  }
  const pipeline::StateStore store(target.directory);
  int status = 0;
  for (auto state : result.learned) {
    // A known-good capture teaches the detector; it does not hand the daemon an alarm.
    state.alarm = pipeline::AlarmState::normal;
    state.alarm_condition = false;
    store.save(state);
    const bool done = detect::has_learned(state.detector);
    fmt::print("actuator {}: {} -> {}\n", state.actuator,
               done ? "learned" : "capture too short, still learning",
               store.file_of(state.actuator).string());
    if (!done) status = 1;
  }
  if (status != 0) {
    fmt::print(stderr,
               "the capture ended before learning did (settle_seconds + learn_seconds of the "
               "detector); the daemon finishes learning from its first minutes\n");
  }
  return status;
}

}  // namespace

int run_state(int argc, char** argv) {
  ArgParser args("state",
                 "show, reset or learn what the daemon keeps across restarts (its state "
                 "directory)");
  args.positional("action",
                  "show (what is saved, and whether it fits --config), reset (delete, so the "
                  "next start learns afresh), learn (from a known-good capture, --in)");
  add_target_options(args);
  args.option("actuator", "NAME", "reset: only this actuator", std::string(""));
  args.option("in", "GOOD.csv", "learn: capture of the healthy rig (FORMATS.md)", std::string(""));
  if (!args.parse(argc, argv)) return 0;
  const std::string action = args.get("action");
  if (action != "show" && action != "reset" && action != "learn") {
    throw UsageError(fmt::format("unknown action '{}' (show, reset or learn)", action));
  }
  const Target target = target_of(args);
  if (action == "show") return show(target);
  if (action == "reset") return reset(target, args.get("actuator"));
  if (args.get("in").empty()) throw UsageError("learn needs --in GOOD.csv");
  return learn(target, args.get("in"));
}

int run_learn(int argc, char** argv) {
  ArgParser args("learn",
                 "learn the healthy rig from a known-good capture and save it to the state "
                 "directory, so the daemon starts from it instead of learning from its first "
                 "minutes (for a rig that may already leak then)");
  args.option("config", "CONFIG.yaml", "daemon configuration (actuators, detector, state)",
              std::nullopt, true);
  args.option("in", "GOOD.csv", "capture of the healthy rig (FORMATS.md)", std::nullopt, true);
  args.option("state-dir", "DIR", "state directory (default: the configuration's state.directory)",
              std::string(""));
  if (!args.parse(argc, argv)) return 0;
  return learn(target_of(args), args.get("in"));
}

}  // namespace leakmon::cli
