// `leakmon sim`: runs the rig model (sim/) for a preset or a scenario file and writes the
// capture CSV of FORMATS.md, with t,xref,u,x,p1,p2,q_int (plus ps and temp when recorded) and
// metadata naming the origin, seed, injected effects, drifting conditions, sensor faults and
// non-nominal parameters.
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "config/yaml_reader.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "sim/summary.hpp"

namespace leakmon::cli {

int run_sim(int argc, char** argv) {
  ArgParser args("sim", fmt::format("Simulates the test rig of MODEL.md and writes a capture CSV.\n"
                                    "Give exactly one of --preset or --scenario. Presets: {}.\n"
                                    "Scenario files are YAML (examples in sim/scenarios/); they\n"
                                    "also set oil temperature, supply set-point changes and\n"
                                    "sensor faults (docs/simulation.md).",
                                    fmt::join(sim::preset_names(), ", ")));
  args.option("preset", "NAME", "a built-in experiment, e.g. paper-fig13", std::nullopt)
      .option("scenario", "SCENARIO.yaml", "a scenario file", std::nullopt)
      .option("out", "CAPTURE.csv", "where to write the capture", std::nullopt, true)
      .option("seed", "N", "random seed (overrides the scenario's)", std::nullopt)
      .option("duration", "SECONDS", "run length (overrides the preset's or scenario's)",
              std::nullopt)
      .option("record", "COLUMNS",
              "optional columns to record as well, comma-separated: ps (supply pressure), temp "
              "(oil temperature)",
              std::nullopt);
  if (!args.parse(argc, argv)) return 0;

  const auto preset_name = args.find("preset");
  const auto scenario_path = args.find("scenario");
  if (preset_name.has_value() == scenario_path.has_value()) {
    throw UsageError("give exactly one of --preset NAME or --scenario SCENARIO.yaml");
  }
  std::uint64_t seed = 1;
  if (args.has("seed")) {
    const long long value = args.get_int("seed");
    if (value < 0) throw UsageError(fmt::format("option '--seed': must be >= 0, got {}", value));
    seed = static_cast<std::uint64_t>(value);
  }

  sim::Scenario scenario;
  if (preset_name) {
    try {
      scenario = sim::preset(*preset_name, seed);
    } catch (const std::invalid_argument& e) {
      throw UsageError(fmt::format("option '--preset': {}", e.what()));
    }
  } else {
    scenario = sim::load_scenario(*scenario_path);  // config::ConfigError: file:line:column
    if (args.has("seed")) scenario.seed = seed;
    for (const auto& warning : scenario.warnings) fmt::print(stderr, "warning: {}\n", warning);
  }
  if (args.has("duration")) {
    const double duration = args.get_double("duration");
    if (!(duration > 0.0 && duration <= 1e6)) {
      throw UsageError(fmt::format("option '--duration': must be in (0, 1e6] s, got {}", duration));
    }
    scenario.duration_s = duration;
  }
  if (args.has("record")) {
    const std::string list = args.get("record");
    std::size_t begin = 0;
    while (begin <= list.size()) {
      const std::size_t end = std::min(list.find(',', begin), list.size());
      const std::string column = list.substr(begin, end - begin);
      if (column == "ps") {
        scenario.record.ps = true;
      } else if (column == "temp") {
        scenario.record.temp = true;
      } else {
        throw UsageError(
            fmt::format("option '--record': unknown column '{}' (allowed: ps, temp)", column));
      }
      begin = end + 1;
    }
  }
  // What the capture will hold, before the run (minutes for a long one): a shortened run that
  // ends before its leak is said, not silent.
  fmt::print(stderr, "leakmon sim: {} -> {}\n", sim::summary_line(scenario), args.get("out"));
  for (const auto& warning : sim::starts_after_end(scenario)) {
    fmt::print(stderr, "leakmon sim: warning: {}\n", warning);
  }
  sim::simulate_to_file(scenario, args.get("out"));
  return 0;
}

}  // namespace leakmon::cli
