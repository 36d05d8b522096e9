// `leakmon sim`: runs the rig model (sim/) for a preset or a scenario file and writes the
// capture CSV of FORMATS.md, with t,xref,u,x,p1,p2,q_int and metadata naming the origin,
// seed, injected effects and non-nominal parameters.
#include <fmt/format.h>

#include <stdexcept>
#include <string>

#include "config/yaml_reader.hpp"
#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"

namespace leakmon::cli {

int run_sim(int argc, char** argv) {
  ArgParser args("sim", fmt::format("Simulates the test rig of MODEL.md and writes a capture CSV.\n"
                                    "Give exactly one of --preset or --scenario. Presets: {}.\n"
                                    "Scenario files are YAML (examples in sim/scenarios/).",
                                    fmt::join(sim::preset_names(), ", ")));
  args.option("preset", "NAME", "a built-in experiment, e.g. paper-fig13", std::nullopt)
      .option("scenario", "SCENARIO.yaml", "a scenario file", std::nullopt)
      .option("out", "CAPTURE.csv", "where to write the capture", std::nullopt, true)
      .option("seed", "N", "random seed (overrides the scenario's)", std::nullopt)
      .option("duration", "SECONDS", "run length (overrides the preset's or scenario's)",
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
  }
  if (args.has("duration")) {
    const double duration = args.get_double("duration");
    if (!(duration > 0.0 && duration <= 1e6)) {
      throw UsageError(fmt::format("option '--duration': must be in (0, 1e6] s, got {}", duration));
    }
    scenario.duration_s = duration;
  }
  sim::simulate_to_file(scenario, args.get("out"));
  return 0;
}

}  // namespace leakmon::cli
