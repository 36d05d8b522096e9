// `leakmon replay --in CAPTURE.csv --events EVENTS.jsonl [--config CONFIG.yaml] [--realtime]`
// (FORMATS.md): a capture through the daemon's pipeline (pipeline/replay.hpp).
#include <fmt/format.h>

#include <fstream>

#include "capture/capture.hpp"
#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/replay.hpp"

namespace leakmon::cli {

int run_replay(int argc, char** argv) {
  ArgParser args("replay", "feed a capture through the daemon's pipeline and write its events");
  args.option("in", "CAPTURE.csv", "capture to replay (FORMATS.md)", std::nullopt, true);
  args.option("events", "EVENTS.jsonl", "where to write the events, one JSON object per line",
              std::nullopt, true);
  args.option("config", "CONFIG.yaml",
              "daemon configuration for actuators, detector and alarms (default: built-in)",
              std::string(""));
  args.flag("realtime", "pace at the capture's own rate instead of as fast as possible");
  args.option("state-dir", "DIR",
              "behave as a daemon restart: resume from what DIR holds for this configuration, "
              "save there at the end",
              std::string(""));
  if (!args.parse(argc, argv)) return 0;

  auto capture = std::make_shared<const capture::Capture>(capture::read_capture(args.get("in")));
  const daemon::DaemonConfig config = args.get("config").empty()
                                          ? pipeline::default_replay_config(*capture)
                                          : daemon::load_config(args.get("config"));
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
  return 0;
}

}  // namespace leakmon::cli
