// `leakmon replay --in CAPTURE.csv --events EVENTS.jsonl [--config CONFIG.yaml | --rig RIG.yaml]
// [--realtime]`
// (FORMATS.md): a capture through the daemon's pipeline (pipeline/replay.hpp).
#include <fmt/format.h>

#include <fstream>
#include <optional>

#include "capture/capture.hpp"
#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/learning_report.hpp"
#include "pipeline/replay.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::cli {

int run_replay(int argc, char** argv) {
  ArgParser args("replay", "feed a capture through the daemon's pipeline and write its events");
  args.option("in", "CAPTURE.csv", "capture to replay (FORMATS.md)", std::nullopt, true);
  args.option("events", "EVENTS.jsonl", "where to write the events, one JSON object per line",
              std::nullopt, true);
  args.option("config", "CONFIG.yaml",
              "daemon configuration for actuators, detector and alarms (default: built-in)",
              std::string(""));
  args.option("rig", "RIG.yaml",
              "the built-in defaults on this rig: a file whose top-level key is rig: "
              "(FORMATS.md); not with --config, whose actuators carry their own rig:",
              std::string(""));
  args.flag("realtime", "pace at the capture's own rate instead of as fast as possible");
  args.option("state-dir", "DIR",
              "behave as a daemon restart: resume from what DIR holds for this configuration, "
              "save there at the end",
              std::string(""));
  if (!args.parse(argc, argv)) return 0;

  if (!args.get("config").empty() && !args.get("rig").empty()) {
    throw UsageError(
        "give --config or --rig, not both: with --config, describe the rig in the actuator's "
        "rig: (FORMATS.md)");
  }
  // Read before the capture, so that a mistake in it is reported at once.
  std::optional<sim::RigDescription> rig;
  if (!args.get("rig").empty()) rig = sim::load_rig_file(args.get("rig"));
  auto capture = std::make_shared<const capture::Capture>(capture::read_capture(args.get("in")));
  daemon::DaemonConfig config = args.get("config").empty()
                                    ? pipeline::default_replay_config(*capture)
                                    : daemon::load_config(args.get("config"));
  if (rig) pipeline::apply_rig(config.actuators.front(), *rig);
  for (const auto& warning : config.warnings) fmt::print(stderr, "warning: {}\n", warning);
  pipeline::ReplayOptions options;
  options.realtime = args.flag_set("realtime");
  options.state_directory = args.get("state-dir");
  const auto result = pipeline::replay_capture(capture, config, options);

  std::ofstream out(args.get("events"));
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write", args.get("events")));
  for (const auto& event : result.events) {
    out << pipeline::to_json_line(event) << '\n';
    if (event.kind == io::EventKind::state_discarded) {
      fmt::print(stderr, "warning: {}\n", event.message);
    }
  }
  out.close();
  if (!out) throw std::runtime_error(fmt::format("{}: write failed", args.get("events")));
  fmt::print(stderr, "{}: {} samples, {} events -> {}\n", args.get("in"), result.samples_processed,
             result.events.size(), args.get("events"));
  // Which detector ran and when it stopped learning: a leak the capture opens while the
  // detector still learns is learned as healthy, and the events alone would not say so.
  for (const auto& status : result.actuators) {
    for (const auto& actuator : config.actuators) {
      if (actuator.name != status.name) continue;
      fmt::print(stderr, "{}\n", pipeline::detector_line(actuator, status));
      if (const auto line = pipeline::learning_line(status); !line.empty()) {
        fmt::print(stderr, "{}\n", line);
      }
    }
  }
  // A step during learning (detect/learned_change.hpp): the leak the events cannot show.
  for (const auto& event : result.events) {
    if (event.kind == io::EventKind::learned_change) {
      fmt::print(stderr, "warning: {}\n", event.message);
    }
  }
  return 0;
}

}  // namespace leakmon::cli
