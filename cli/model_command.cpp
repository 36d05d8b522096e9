// `leakmon model check` and `leakmon model evaluate` (FORMATS.md, issue 7): where the rig
// simulation disagrees with measured data, which effect of MODEL.md's library explains it,
// and how well the workflow does on cases drawn afresh from MODEL.md.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "capture/capture.hpp"
#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "model/diagnosis.hpp"
#include "model/effect_library.hpp"
#include "model/evaluation.hpp"
#include "model/measured_record.hpp"
#include "model/report.hpp"
#include "model/result_json.hpp"
#include "model/rig_source.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::cli {
namespace {

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(fmt::format("{}: cannot write", path));
}

int run_check(int argc, char** argv) {
  ArgParser args(
      "model check",
      "Checks the rig's stated values that the capture can check (supply, load\n"
      "stiffness), calibrates beta, Kv, m, b around the stated ones on the fitting part\n"
      "of a capture, extends the model with each effect of MODEL.md's library, scores\n"
      "each on held-out data and names the best when its gain is significant (else\n"
      "`none`). Writes FORMATS.md's JSON. Without --rig or --config the rig is the\n"
      "paper's (MODEL.md's nominal values).");
  args.option("data", "CAPTURE.csv", "capture with at least t,u,x,p1,p2 at 500 Hz", std::nullopt,
              true)
      .option("json", "RESULT.json", "where to write the result", std::nullopt, true)
      .option("rig", "RIG.yaml", "the rig's description: a file whose top-level key is rig:", "")
      .option("config", "CONFIG.yaml", "the daemon's configuration: take --actuator's rig:", "")
      .option("actuator", "NAME", "the actuator of --config whose rig: to take", "")
      .option("report", "DIR", "also write a Markdown report with plots into DIR", "");
  if (!args.parse(argc, argv, 2)) return 0;
  const std::string rig_file = args.get("rig");
  const std::string config_file = args.get("config");
  const std::string actuator = args.get("actuator");
  if (!rig_file.empty() && !config_file.empty()) {
    throw UsageError("give the rig once: --rig RIG.yaml or --config CONFIG.yaml --actuator NAME");
  }
  if (config_file.empty() != actuator.empty()) {
    throw UsageError(
        "--config and --actuator go together: the actuator of the configuration "
        "whose rig: the capture was recorded on");
  }
  sim::RigDescription rig = sim::RigDescription::paper();
  if (!rig_file.empty()) rig = sim::load_rig_file(rig_file);
  if (!config_file.empty()) rig = model::load_actuator_rig(config_file, actuator);
  const model::MeasuredRecord record = model::read_measured_record(args.get("data"));
  fmt::print("rig: {}\n", sim::describe(rig));
  const model::Diagnosis d = model::diagnose(record, rig);
  write_text(args.get("json"), model::diagnosis_json(d));
  for (const auto& finding : d.rig_check.findings) {
    fmt::print("stated {} {:.4g} contradicted by the data: {:.4g}\n", finding.parameter,
               finding.stated, finding.fitted);
  }
  fmt::print("cause: {} (held-out NRMSE {:.4f} -> {:.4f})\n", d.cause, d.nrmse_before,
             d.nrmse_after);
  if (const auto dir = args.get("report"); !dir.empty()) {
    if (!model::write_report(dir, record, d)) {
      fmt::print(stderr, "leakmon model check: plots failed, see {}/plots.log\n", dir);
    }
    fmt::print("report: {}/report.md\n", dir);
  }
  return 0;
}

int run_evaluate_cases(int argc, char** argv) {
  ArgParser args("model evaluate",
                 "Draws cases afresh from MODEL.md (each effect of the library and none in turn,\n"
                 "parameters, calibration, controller and reference at random), simulates them\n"
                 "with sensor and spool noise and runs the model check on each. Writes\n"
                 "OUT/cases.csv and OUT/summary.md (accuracy and confusion matrix).");
  args.option("cases", "N", "number of cases", "24")
      .option("seed", "S", "seed of the first case; case i uses S + i", "1")
      .option("first-case", "K",
              "start at case K of the sequence (its seed S + K, its class and effect), to "
              "resume a run or draw one case of it again: --first-case 33 --cases 34",
              "0")
      .option("duration", "SECONDS", "length of each simulated capture", "60")
      .option("classes", "LIST",
              "comma-separated case classes, taken in turn: library (the eleven effects and "
              "none), pair, warmup_temp, warmup_no_temp, edge, beyond, clean, misstated (a "
              "stated value wrong), onset (an effect appearing inside the capture)",
              "library")
      .option("rigs", "WHICH",
              "paper (MODEL.md's rig) or other (rigs drawn from MODEL.md's 'Other rigs' "
              "ranges, each told its description; classes misstated and onset as well)",
              "paper")
      .flag("programs",
            "each capture runs a random test program (MODEL.md 'Test programs': 3-8 phases of "
            "steps, holds, sines, sweeps and triangles, shortened alike to fit the capture, "
            "amplitudes as the rig's steps) instead of the paper's steps")
      .option("out", "DIR", "output directory", std::nullopt, true)
      .flag("keep-captures",
            "also write each case's capture (OUT/case-SEED.csv) and the rig it was told "
            "(OUT/case-SEED-rig.yaml), for `leakmon model check --rig`");
  if (!args.parse(argc, argv, 2)) return 0;
  const long long cases = args.get_int("cases");
  if (cases < 1) throw UsageError("option '--cases': must be at least 1");
  const auto first = static_cast<std::uint64_t>(args.get_int("seed"));
  const long long first_case = args.get_int("first-case");
  if (first_case < 0 || first_case >= cases) {
    throw UsageError("option '--first-case': must be at least 0 and less than --cases");
  }
  model::CaseSettings case_settings;
  case_settings.duration_s = args.get_double("duration");
  const std::string rigs = args.get("rigs");
  if (rigs != "paper" && rigs != "other") {
    throw UsageError(fmt::format("option '--rigs': '{}' is neither paper nor other", rigs));
  }
  case_settings.other_rig = rigs == "other";
  case_settings.program = args.flag_set("programs");
  std::vector<std::string> kinds;
  const std::string list = args.get("classes");
  for (std::size_t begin = 0; begin <= list.size();) {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    const std::string kind = list.substr(begin, end - begin);
    const auto& known = model::case_kinds();
    if (std::find(known.begin(), known.end(), kind) == known.end()) {
      throw UsageError(fmt::format("option '--classes': unknown class '{}'", kind));
    }
    kinds.push_back(kind);
    begin = end + 1;
  }
  const std::string dir = args.get("out");
  std::filesystem::create_directories(dir);
  model::EvaluationSummary summary;
  for (long long i = first_case; i < cases; ++i) {
    const auto index = static_cast<std::size_t>(i);
    const auto& kind = kinds[index % kinds.size()];
    const auto [effect, settings] = model::case_of_kind(kind, index / kinds.size(), case_settings);
    const auto seed = first + static_cast<std::uint64_t>(i);
    if (args.flag_set("keep-captures")) {
      const model::SyntheticCase c = model::draw_case(seed, effect, settings);
      capture::write_capture(fmt::format("{}/case-{}.csv", dir, seed), model::simulate_case(c));
      write_text(fmt::format("{}/case-{}-rig.yaml", dir, seed), sim::rig_file_text(c.told));
    }
    summary.cases.push_back(model::evaluate_case(seed, effect, settings));
    summary.cases.back().kind = kind;
    const auto& c = summary.cases.back();
    fmt::print(
        "case {} seed {}: {} -> {} ({} true {:.4g} est {:.4g}) nrmse {:.4f} -> {:.4f} "
        "{:.1f} s; leading {} score {:.4f} t {:.2f}; line z {:.2f}\n",
        i, seed, c.truth, c.named, c.main_parameter, c.true_value, c.estimate, c.nrmse_before,
        c.nrmse_after, c.seconds, c.leading, c.leading_score, c.leading_significance, c.line_z);
    fmt::print("  {} causes [{}] floor {:.4f} true {:.4f} achieved {:.2f} drifts {} steps {}\n",
               c.kind, c.causes, c.nrmse_floor, c.nrmse_true, c.achieved, c.drifts, c.steps);
    if (case_settings.other_rig || !c.misstated.empty() || c.onset_true > 0.0) {
      std::string findings;
      for (const auto& f : c.rig_findings) {
        findings += fmt::format(" {} {:.4g}->{:.4g}", f.parameter, f.stated, f.fitted);
      }
      fmt::print(
          "  rig {}; misstated {} (true {:.4g} told {:.4g}); found{}; onset {:.2f} -> {:.2f}\n",
          c.rig, c.misstated.empty() ? "-" : c.misstated, c.misstated_true, c.misstated_stated,
          findings.empty() ? " nothing" : findings, c.onset_true, c.onset_estimate);
    }
    if (!c.program.empty()) fmt::print("  program {}\n", c.program);
    std::fflush(stdout);
  }
  write_text(dir + "/cases.csv", summary.csv());
  const std::string markdown =
      summary.targets_markdown() + "\n" + summary.kind_markdown() + "\n" + summary.markdown();
  write_text(dir + "/summary.md", markdown);
  fmt::print("{}", markdown);
  return 0;
}

}  // namespace

int run_model(int argc, char** argv) {
  const std::string_view usage =
      "usage: leakmon model check --data CAPTURE.csv --json RESULT.json\n"
      "                           [--rig RIG.yaml | --config CONFIG.yaml --actuator NAME]\n"
      "                           [--report DIR]\n"
      "       leakmon model evaluate --out DIR [--cases N] [--seed S] [--duration SECONDS]\n"
      "                              [--classes LIST] [--rigs paper|other] [--programs]\n";
  if (argc < 2) throw UsageError(std::string(usage));
  const std::string_view action = argv[1];
  if (action == "-h" || action == "--help") {
    fmt::print("{}", usage);
    return 0;
  }
  if (action == "check") return run_check(argc, argv);
  if (action == "evaluate") return run_evaluate_cases(argc, argv);
  throw UsageError(fmt::format("unknown action '{}'\n{}", action, usage));
}

}  // namespace leakmon::cli
