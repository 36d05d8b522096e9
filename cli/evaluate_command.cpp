// `leakmon evaluate`: Monte-Carlo error rates of the leak detectors. Draws rigs across MODEL.md's
// calibration spread (both controllers, spring 40-120 kN/m, beta, Kv, m, b, reference
// amplitudes and seeds), healthy runs and runs with a leak switched on mid-run, simulates each
// (sim/) and replays it in process through exactly the daemon's pipeline
// (pipeline::replay_capture). Every detector under test is one actuator of the replayed
// configuration, at several alarm thresholds, so one replay yields the whole ROC sweep. Writes
// runs.json (every run and alarm), summary.json, summary.tsv, summary.md, conditions.md and
// conditions.tsv into --out (programs.tsv and wear.tsv under those conditions), and the plots
// when --plots is given (docs/tools/detection_plots.py). The harness is study/ (case
// generation, runner, aggregation, writers); this front end parses the options and calls it.
#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "sim/effects.hpp"
#include "study/case_generation.hpp"
#include "study/evaluation_options.hpp"
#include "study/evaluation_runner.hpp"
#include "study/evaluation_writers.hpp"
#include "study/rig_cases.hpp"

namespace leakmon::cli {

namespace {

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

std::vector<double> parse_list(const std::string& option, const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      values.push_back(std::stod(item));
    } catch (const std::exception&) {
      throw UsageError(fmt::format("option '--{}': '{}' is not a number", option, item));
    }
  }
  return values;
}

}  // namespace

int run_evaluate(int argc, char** argv) {
  ArgParser args("evaluate",
                 "Monte-Carlo error rates of the leak detectors on simulated rigs, each capture\n"
                 "replayed through the daemon's pipeline. Writes runs.json, summary.json,\n"
                 "summary.tsv and summary.md into --out (and plots with --plots).");
  args.option("out", "DIR", "output directory", std::nullopt, true)
      .option("healthy-runs", "N", "healthy runs (false-alarm rate)", "8")
      .option("healthy-seconds", "S", "length of each healthy run", "900")
      .option("runs-per-leak", "N", "runs per leak size", "6")
      .option("leaks", "LIST", "leak sizes C_L [m^3/(s Pa)], comma-separated",
              "1e-13,2.5e-13,5e-13,1e-12,2e-12,5e-12")
      .option("learn-seconds", "S", "each detector's learning period", "90")
      .option("after-onset", "S", "run length after the leak onset", "90")
      .option("seed", "N", "master seed", "1")
      .option("jobs", "N", "parallel runs", "2")
      .option("effects", "LIST",
              "MODEL.md effects switched on in every run (default parameters), comma-separated", "")
      .option("conditions", "LIST",
              "operating conditions the runs cycle through, comma-separated: stationary, warmup, "
              "cooler, supply, sensor-faults, restart, programs, wear (MODEL.md drifting "
              "conditions and sensor faults; restart: stopped after learning, restarted from the "
              "saved state after a downtime in which the oil changed by 1-5 K and a leak run's "
              "leak opened; programs: random test programs of 3-8 phases, healthy runs as long as "
              "their program, leak runs opening in each phase kind in turn; wear: leak runs whose "
              "C_L grows from 0 to 1e-12..5e-12 over 10 min to 4 h, the oil cycling with the "
              "cooler); adds conditions.md and conditions.tsv, and programs.tsv, wear.tsv",
              "stationary")
      .option("sensor-fault-runs", "N",
              "extra runs with one sensor fault each (the six kinds in turn, each kind's runs "
              "alternately with a 1e-12 leak opening during the fault), scored per fault kind in "
              "conditions.md",
              "0")
      .option("after-restart", "S", "how long a healthy restart is watched", "300")
      .option("time-scale", "X",
              "programs and wear: phase lengths and wear times are MODEL.md's typical values "
              "times X (less than 1 for a quick check)",
              "1")
      .option("rigs", "paper|other",
              "paper: the paper's rig across MODEL.md's calibration spread; other: each run on a "
              "rig drawn from MODEL.md \"Other rigs\", leak sizes relative to its valve (C_L = "
              "size x Kv / 3.39e-7), the default detector on three sets of channels told the rig "
              "and not told; writes rigs.md, rigs.tsv and rigs_runs.tsv (and with programs or "
              "wear their tables per phase kind and growth rate; not with restart or sensor "
              "faults; programs scaled as the rig's steps, supply changes as its supply)",
              "paper")
      .option("keep-captures", "IDS", "write these runs' captures (run-ID.csv), comma-separated",
              "")
      .flag("plots", "also draw the plots (matplotlib via /usr/bin/python3)")
      .option("plot-script", "PATH", "the plotting script", "docs/tools/detection_plots.py");
  if (!args.parse(argc, argv)) return 0;

  study::EvaluationOptions settings;
  settings.healthy_runs = static_cast<int>(args.get_int("healthy-runs"));
  settings.healthy_seconds = args.get_double("healthy-seconds");
  settings.runs_per_leak = static_cast<int>(args.get_int("runs-per-leak"));
  settings.leak_sizes = parse_list("leaks", args.get("leaks"));
  settings.learn_seconds = args.get_double("learn-seconds");
  settings.after_onset_seconds = args.get_double("after-onset");
  settings.seed = static_cast<std::uint64_t>(args.get_int("seed"));
  settings.jobs = static_cast<int>(args.get_int("jobs"));
  settings.effects = split(args.get("effects"));
  for (const auto& effect : settings.effects) {
    try {
      sim::Effects().enable(effect);
    } catch (const std::exception& e) {
      throw UsageError(fmt::format("option '--effects': {}", e.what()));
    }
  }
  settings.sensor_fault_runs = static_cast<int>(args.get_int("sensor-fault-runs"));
  settings.after_restart_seconds = args.get_double("after-restart");
  settings.time_scale = args.get_double("time-scale");
  settings.conditions = split(args.get("conditions"));
  for (const auto& condition : settings.conditions) {
    if (!study::is_condition(condition)) {
      throw UsageError(fmt::format(
          "option '--conditions': unknown condition '{}' (known: stationary, warmup, cooler, "
          "supply, sensor-faults, restart, programs, wear)",
          condition));
    }
  }
  if (settings.conditions.empty()) settings.conditions = {"stationary"};
  if (settings.healthy_runs < 0 || settings.runs_per_leak < 0 || settings.sensor_fault_runs < 0 ||
      settings.jobs < 1 || !(settings.after_restart_seconds > 0.0) ||
      !(settings.time_scale > 0.0 && settings.time_scale <= 100.0)) {
    throw UsageError(
        "run counts must be >= 0, --jobs >= 1, --after-restart > 0 and 0 < --time-scale <= 100");
  }
  if (settings.learn_seconds < 1 || settings.healthy_seconds < settings.learn_seconds + 10 ||
      settings.after_onset_seconds < settings.detect_within) {
    throw UsageError(
        "need --learn-seconds >= 1, --healthy-seconds >= learn + 10, --after-onset >= 60");
  }
  settings.rigs = args.get("rigs");
  if (settings.rigs != "paper" && settings.rigs != "other") {
    throw UsageError(fmt::format("option '--rigs': '{}' is not paper or other", settings.rigs));
  }
  if (settings.rigs == "other") {
    // The rig runner replays one capture per run: a restart's second capture and the sensor
    // fault tables are the paper's rig's.
    for (const auto& condition : settings.conditions) {
      if (condition == "restart" || condition == "sensor-faults") {
        throw UsageError(fmt::format(
            "--rigs other does not run the '{}' condition (known there: stationary, warmup, "
            "cooler, supply, programs, wear)",
            condition));
      }
    }
    if (settings.sensor_fault_runs > 0) {
      throw UsageError("--rigs other does not run --sensor-fault-runs");
    }
  }
  for (double id : parse_list("keep-captures", args.get("keep-captures"))) {
    settings.keep_captures.push_back(static_cast<int>(id));
  }
  const std::filesystem::path out = args.get("out");
  settings.out = out;
  std::filesystem::create_directories(out);

  const std::vector<study::RunSpec> runs = study::draw_runs(settings);
  const auto show_progress = [](std::size_t done, std::size_t total) {
    fmt::print(stderr, "\r[{}/{}] runs evaluated", done, total);
    std::fflush(stderr);
  };
  if (settings.rigs == "other") {
    std::vector<study::RigRunResult> rig_results;
    try {
      rig_results = study::run_rig_evaluation(runs, settings, show_progress);
    } catch (...) {
      fmt::print(stderr, "\n");
      throw;
    }
    fmt::print(stderr, "\n");
    study::write_rig_summaries(out, settings, rig_results);
    fmt::print("wrote {}/rigs.md, rigs.tsv, rigs_runs.tsv\n", out.string());
    return 0;
  }
  std::vector<study::RunResult> results;
  try {
    results = study::run_evaluation(runs, settings, show_progress);
  } catch (...) {
    fmt::print(stderr, "\n");
    throw;
  }
  fmt::print(stderr, "\n");

  study::write_runs_json(out / "runs.json", results);
  study::write_summaries(out, settings, results);
  study::write_condition_summaries(out, settings, results);
  fmt::print(
      "wrote {}/runs.json, summary.json, summary.tsv, summary.md, size_coverage.tsv, "
      "conditions.md, conditions.tsv{}{}\n",
      out.string(), std::filesystem::exists(out / "programs.tsv") ? ", programs.tsv" : "",
      std::filesystem::exists(out / "wear.tsv") ? ", wear.tsv" : "");

  if (args.flag_set("plots")) {
    const std::string command =
        fmt::format("/usr/bin/python3 '{}' '{}'", args.get("plot-script"), out.string());
    if (std::system(command.c_str()) != 0) {
      throw std::runtime_error("plotting failed: " + command);
    }
  }
  return 0;
}

}  // namespace leakmon::cli
