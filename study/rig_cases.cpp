#include "study/rig_cases.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <variant>

#include "pipeline/mode_visibility.hpp"
#include "pipeline/replay.hpp"
#include "sim/rig_draw.hpp"
#include "sim/simulate.hpp"
#include "study/evaluation_summary.hpp"

namespace leakmon::study {
namespace {

// The rate and level the replayed actuators' index uses (the daemon's defaults).
constexpr double kSampleRateHz = 500.0;
constexpr int kIndexLevel = 2;

std::string actuator_of(std::size_t candidate) { return fmt::format("r{}", candidate); }

std::size_t candidate_of(const std::string& actuator, std::size_t count) {
  if (actuator.size() < 2 || actuator[0] != 'r') return count;
  try {
    return std::stoul(actuator.substr(1));
  } catch (const std::exception&) {
    return count;
  }
}

bool pressure_only(const RigCandidate& c) { return !c.u && !c.x; }

std::string delay_text(const std::vector<double>& delays) {
  if (delays.empty()) return "-";
  std::vector<double> sorted = delays;
  std::sort(sorted.begin(), sorted.end());
  return fmt::format("{:.1f} s", sorted[sorted.size() / 2]);
}

std::string found_text(const Rates& r) {
  if (r.leak_runs == 0) return "-";
  const Interval ci = r.detection_rate_95();
  return fmt::format("{}/{} ({:.0f} %, {:.0f}-{:.0f})", r.detected, r.leak_runs,
                     100.0 * r.detection_rate(), 100.0 * ci.lower, 100.0 * ci.upper);
}

std::string size_error_text(const Rates& r) {
  const double e = r.median_abs_size_error();
  return std::isfinite(e) ? fmt::format("{:.0f} %", 100.0 * e) : "-";
}

std::string candidate_label(const RigCandidate& c) {
  return fmt::format("{} ({})", c.label, c.told ? "told" : "not told");
}

std::string percent_of(int k, int n) {
  if (n == 0) return "-";
  return fmt::format("{}/{} ({:.0f} %)", k, n, 100.0 * k / n);
}

// Test programs and seals that wear on other rigs: rigs.md's tables per phase kind, per program
// start and per growth rate for every candidate, and rigs_programs.tsv / rigs_wear.tsv.
void write_rig_condition_tables(fmt::ostream& md, const std::filesystem::path& dir,
                                const EvaluationOptions& options,
                                const std::vector<RigRunResult>& results) {
  std::vector<RunResult> runs;
  bool programs = false, wear = false;
  for (const auto& r : results) {
    runs.push_back(r.run);
    programs = programs || (!r.run.spec.phases.empty() && !r.run.spec.wear_run());
    wear = wear || (r.run.spec.wear_run() && r.run.spec.leak > 0.0);
  }
  const auto all = rig_candidates();
  if (programs) {
    auto tsv = fmt::output_file((dir / "rigs_programs.tsv").string());
    tsv.print(
        "channels\ttold\tphase\thealthy_hours\tfalse_alarms\tfa_upper_95\tleak_runs\tfound\t"
        "found_late\tmedian_delay\n");
    md.print(
        "\nTest programs per phase kind (the phases' positions and amplitudes scaled as the rig's "
        "steps). Healthy time: monitored, before any onset, in phases of the kind; a false alarm "
        "counts in the phase it was raised in. A leak counts in the phase it opened in and is "
        "found when raised within {0:.0f} s of its onset, or, in a hold whose |K_s X| / A stays "
        "below {1:g} MPa (not judgeable), within {0:.0f} s of the next phase's start.\n\n"
        "| channels | phase | healthy h | false alarms (95 % upper bound per h) | leaks found in "
        "time | found later | median delay |\n|---|---|---|---|---|---|---|\n",
        options.detect_within, kJudgeableLoad / 1e6);
    for (std::size_t c = 0; c < all.size(); ++c) {
      for (const PhaseKindScore& row : score_program_phases(runs, c, options.detect_within, 0)) {
        if (row.healthy_hours <= 0.0 && row.leak_runs == 0) continue;
        md.print("| {} | {} | {:.2f} | {} ({:.2f}) | {} | {} | {} |\n", candidate_label(all[c]),
                 row.phase, row.healthy_hours, row.false_alarms,
                 row.false_alarms_per_hour_upper_95(), percent_of(row.found, row.leak_runs),
                 row.found_late, delay_text(row.delays));
        std::vector<double> delays = row.delays;
        std::sort(delays.begin(), delays.end());
        tsv.print("{}\t{}\t{}\t{:.4g}\t{}\t{:.4g}\t{}\t{}\t{}\t{:.4g}\n", all[c].label,
                  all[c].told ? 1 : 0, row.phase, row.healthy_hours, row.false_alarms,
                  row.false_alarms_per_hour_upper_95(), row.leak_runs, row.found, row.found_late,
                  delays.empty() ? NAN : delays[delays.size() / 2]);
      }
    }
    md.print(
        "\nBy how the program starts:\n\n| channels | program starts with | runs | healthy h | "
        "false alarms | runs with a false alarm |\n|---|---|---|---|---|---|\n");
    for (std::size_t c = 0; c < all.size(); ++c) {
      for (const ProgramStartScore& row : score_program_starts(runs, c, 0)) {
        md.print("| {} | {} | {} | {:.2f} | {} | {} |\n", candidate_label(all[c]),
                 row.starts_with_hold ? "a hold" : "another phase", row.runs, row.healthy_hours,
                 row.false_alarms, row.runs_with_false_alarm);
      }
    }
  }
  if (wear) {
    auto tsv = fmt::output_file((dir / "rigs_wear.tsv").string());
    tsv.print("channels\ttold\tgrowth\truns\tfound\tfound_before_target\tmedian_found_at\n");
    md.print(
        "\nSeals that wear (C_L from 0 to 1e-12..5e-12 x Kv / 3.39e-7 over 10 min to 4 h; sizes "
        "as the paper's valve's equivalent, C_L x 3.39e-7 / Kv; found = the first raise after the "
        "wear began):\n\n| channels | found | found before {:g} | median size when found | slow "
        "| medium | fast |\n|---|---|---|---|---|---|---|\n",
        kWearTarget);
    for (std::size_t c = 0; c < all.size(); ++c) {
      const std::vector<WearScore> rows = score_wear(runs, c, 0);
      std::vector<double> sizes = rows[0].found_at;
      std::sort(sizes.begin(), sizes.end());
      md.print("| {} | {}/{} | {} | {} | {}/{} | {}/{} | {}/{} |\n", candidate_label(all[c]),
               rows[0].found, rows[0].runs, percent_of(rows[0].found_before_target, rows[0].runs),
               sizes.empty() ? std::string("-") : fmt::format("{:.2g}", sizes[sizes.size() / 2]),
               rows[1].found_before_target, rows[1].runs, rows[2].found_before_target, rows[2].runs,
               rows[3].found_before_target, rows[3].runs);
      for (const WearScore& row : rows) {
        std::vector<double> at = row.found_at;
        std::sort(at.begin(), at.end());
        tsv.print("{}\t{}\t{}\t{}\t{}\t{}\t{:.4g}\n", all[c].label, all[c].told ? 1 : 0, row.growth,
                  row.runs, row.found, row.found_before_target,
                  at.empty() ? NAN : at[at.size() / 2]);
      }
    }
  }
}

}  // namespace

double paper_equivalent_leak(const RunSpec& run) {
  const auto* leak = std::get_if<LeakCondition>(&run.condition.kind);
  return leak != nullptr ? leak->coefficient : 0.0;
}

std::vector<RigCandidate> rig_candidates() {
  std::vector<RigCandidate> out;
  for (const bool told : {true, false}) {
    out.push_back({"p1,p2,u,x", true, true, true, told});
    out.push_back({"p1,p2", true, false, false, told});
    out.push_back({"p1", false, false, false, told});
  }
  return out;
}

pipeline::DaemonConfig rig_evaluation_config(const capture::Capture& capture, const RunSpec& run,
                                             const EvaluationOptions& options) {
  pipeline::DaemonConfig config = pipeline::default_replay_config(capture);
  const pipeline::ActuatorConfig base = config.actuators.at(0);
  config.actuators.clear();
  // The run's transducers, for both classes: a user who has not described the rig still knows
  // the range of the transducers they fitted.
  const sim::SensorSettings& sensors = run.scenario.sensors;
  detect::TransducerSpec pressure = detect::TransducerSpec::pressure();
  pressure.max = sensors.pressure_full_scale;
  pressure.resolution = sensors.pressure_lsb();
  pressure.noise_sigma = sensors.pressure_noise_sigma;
  detect::TransducerSpec position = detect::TransducerSpec::position();
  position.resolution = sensors.position_resolution;
  position.noise_sigma = sensors.position_noise_sigma;
  const auto all = rig_candidates();
  for (std::size_t c = 0; c < all.size(); ++c) {
    pipeline::ActuatorConfig a = base;
    a.name = actuator_of(c);
    a.detector = "default";
    a.detector_options = detector_options(options);
    if (!all[c].p2) a.channels[capture::Role::p2] = {};
    if (!all[c].u) a.channels[capture::Role::u] = {};
    if (!all[c].x) a.channels[capture::Role::x] = {};
    a.channels[capture::Role::temp] = {};
    a.channels[capture::Role::ps] = {};
    if (all[c].told) pipeline::apply_rig(a, run.scenario.rig);
    a.transducers[capture::Role::p1] = a.transducers[capture::Role::p2] = pressure;
    a.transducers[capture::Role::x] = position;
    config.actuators.push_back(std::move(a));
  }
  return config;
}

double rest_load_pressure(const sim::Scenario& scenario) {
  const double amplitude = 0.5 * (scenario.reference.amp_min + scenario.reference.amp_max);
  return scenario.params.K_s * amplitude / scenario.params.A();
}

RigRunResult evaluate_rig_run(const RunSpec& spec, const EvaluationOptions& options) {
  const auto all = rig_candidates();
  RigRunResult result;
  result.run.spec = spec;
  result.run.alarms.assign(all.size(), std::vector<std::vector<Alarm>>(1));
  result.blind.assign(all.size(), false);
  result.any_fault.assign(all.size(), false);
  result.mode_hz = sim::hydraulic_mode_hz(spec.scenario.params);
  const auto band = pipeline::ModeVisibilityCheck::readable_band(kSampleRateHz, kIndexLevel);
  result.mode_in_band = result.mode_hz >= band.low && result.mode_hz <= band.high;
  result.rest_load = rest_load_pressure(spec.scenario);

  const capture::Capture capture = sim::simulate(spec.scenario);
  if (std::find(options.keep_captures.begin(), options.keep_captures.end(), spec.id) !=
      options.keep_captures.end()) {
    capture::write_capture((options.out / fmt::format("run-{}.csv", spec.id)).string(), capture);
    // The rig it ran on, for `leakmon replay --rig` (told) beside the plain replay (not told).
    std::ofstream(options.out / fmt::format("run-{}-rig.yaml", spec.id))
        << sim::rig_file_text(spec.scenario.rig);
  }
  const auto replay =
      pipeline::replay_capture(capture, rig_evaluation_config(capture, spec, options));
  for (const auto& event : replay.events) {
    const std::size_t c = candidate_of(event.actuator, all.size());
    if (c >= all.size()) continue;
    if (event.kind == io::EventKind::detection_blind) result.blind[c] = true;
    if (event.kind != io::EventKind::alarm_raised) continue;
    if (event.alarm == "sensor_fault") {
      result.any_fault[c] = true;
      if (result.first_fault.empty()) result.first_fault = event.channel + " " + event.fault;
      continue;
    }
    result.run.alarms[c][0].push_back({event.t, event.leak_coefficient});
  }
  result.run.seconds = spec.scenario.duration_s;
  return result;
}

std::vector<RigRunResult> run_rig_evaluation(const std::vector<RunSpec>& runs,
                                             const EvaluationOptions& options,
                                             const Progress& progress) {
  return run_in_parallel<RigRunResult>(runs, options.jobs, progress, [&](const RunSpec& run) {
    return evaluate_rig_run(run, options);
  });
}

RigScore score_rig_candidate(const std::vector<RigRunResult>& results, std::size_t candidate,
                             const EvaluationOptions& options) {
  RigScore score;
  score.per_size.resize(options.leak_sizes.size());
  for (const auto& r : results) {
    // A seal that wears is scored by the size it is found at (the wear table), not in a window.
    const bool opens = !r.run.spec.wear_run();
    add_run(score.all, r.run, candidate, 0, options.detect_within, true, opens);
    const double size = opens ? paper_equivalent_leak(r.run.spec) : 0.0;
    for (std::size_t k = 0; k < options.leak_sizes.size(); ++k) {
      if (size > 0.0 && size == options.leak_sizes[k]) {
        add_run(score.per_size[k], r.run, candidate, 0, options.detect_within, false, true);
      }
    }
    const bool blind = r.blind[candidate];
    if (r.mode_in_band) {
      ++score.in_band_runs;
      score.in_band_blind += blind ? 1 : 0;
    } else {
      ++score.out_of_band_runs;
      score.out_of_band_blind += blind ? 1 : 0;
    }
    if (!blind) {
      add_run(score.not_blind, r.run, candidate, 0, options.detect_within, false, opens);
    }
    if (r.rest_load >= kSeeableRestLoad) {
      add_run(score.loaded, r.run, candidate, 0, options.detect_within, false, opens);
    }
    score.sensor_fault_runs += r.any_fault[candidate] ? 1 : 0;
  }
  return score;
}

void write_rig_summaries(const std::filesystem::path& dir, const EvaluationOptions& options,
                         const std::vector<RigRunResult>& results) {
  const auto all = rig_candidates();
  std::vector<RigScore> scores;
  for (std::size_t c = 0; c < all.size(); ++c) {
    scores.push_back(score_rig_candidate(results, c, options));
  }
  const auto band = pipeline::ModeVisibilityCheck::readable_band(kSampleRateHz, kIndexLevel);

  auto md = fmt::output_file((dir / "rigs.md").string());
  md.print(
      "Other rigs (MODEL.md \"Other rigs\", sim::draw_other_rig): {} runs, seed {}. Leak sizes "
      "relative to the valve: C_L = size x (Kv / 3.39e-7). Default detector at its design "
      "threshold; found = raised within {:.0f} s of the onset.\n\n",
      results.size(), options.seed, options.detect_within);
  md.print("| channels | told the rig | healthy h | false alarms | per h (95 % upper) |");
  for (const double size : options.leak_sizes) md.print(" found, size {:g} |", size);
  md.print(
      " found, rest load >= {:g} MPa | median delay | median abs size error | detection_blind: "
      "mode out of band / in band | found where not blind | sensor_fault runs |\n"
      "|---|---|---|---|---|",
      kSeeableRestLoad * 1e-6);
  for (std::size_t k = 0; k < options.leak_sizes.size(); ++k) md.print("---|");
  md.print("---|---|---|---|---|---|\n");
  for (std::size_t c = 0; c < all.size(); ++c) {
    const RigScore& s = scores[c];
    md.print("| {} | {} | {:.2f} | {} | {:.3f} ({:.3f}) |", all[c].label,
             all[c].told ? "told" : "not told", s.all.healthy_hours, s.all.false_alarms,
             s.all.false_alarms_per_hour(), s.all.false_alarms_per_hour_upper_95());
    for (const Rates& r : s.per_size) md.print(" {} |", found_text(r));
    md.print(" {} | {} | {} | {}/{} / {}/{} | {} | {} |\n", found_text(s.loaded),
             delay_text(s.all.delays), size_error_text(s.all), s.out_of_band_blind,
             s.out_of_band_runs, s.in_band_blind, s.in_band_runs,
             pressure_only(all[c]) ? found_text(s.not_blind) : std::string("-"),
             s.sensor_fault_runs);
  }
  md.print(
      "\nThe index reads modes within {:.1f}-{:.1f} Hz (pipeline::ModeVisibilityCheck::"
      "readable_band); the detection_blind column counts the runs whose pressure-only actuator "
      "announced it. Rest load: K_s a / A at the steps' mean amplitude a, what a leak flows on "
      "while the flow balance judges it.\n\nRigs drawn:\n\n| run | controller | bore mm | supply "
      "MPa | Kv | mass kg | spring kN/m | rest load MPa | mode Hz | leak C_L |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n",
      band.low, band.high);
  for (const auto& r : results) {
    const auto& p = r.run.spec.scenario.params;
    md.print("| {} | {} | {:.1f} | {:.1f} | {:.3g} | {:.3g} | {:.0f} | {:.2f} | {:.0f} | {} |\n",
             r.run.spec.id, sim::to_string(r.run.spec.scenario.controller), p.D * 1e3, p.ps * 1e-6,
             p.Kv, p.m, p.K_s * 1e-3, r.rest_load * 1e-6, r.mode_hz,
             r.run.spec.leak > 0.0 ? fmt::format("{:.3g}", r.run.spec.leak) : std::string("-"));
  }

  write_rig_condition_tables(md, dir, options, results);

  auto tsv = fmt::output_file((dir / "rigs.tsv").string());
  tsv.print(
      "channels\ttold\thealthy_hours\tfalse_alarms\tfalse_alarms_per_hour_upper_95\tleak_runs\t"
      "found\tloaded_leak_runs\tloaded_found\tmedian_delay_s\tmedian_abs_size_error\t"
      "out_of_band_runs\tout_of_band_blind\tin_band_runs\tin_band_blind\tsensor_fault_runs\n");
  for (std::size_t c = 0; c < all.size(); ++c) {
    const RigScore& s = scores[c];
    tsv.print("{}\t{}\t{:.4f}\t{}\t{:.4f}\t{}\t{}\t{}\t{}\t{:.3f}\t{:.4f}\t{}\t{}\t{}\t{}\t{}\n",
              all[c].label, all[c].told ? 1 : 0, s.all.healthy_hours, s.all.false_alarms,
              s.all.false_alarms_per_hour_upper_95(), s.all.leak_runs, s.all.detected,
              s.loaded.leak_runs, s.loaded.detected, s.all.median_delay(),
              s.all.median_abs_size_error(), s.out_of_band_runs, s.out_of_band_blind,
              s.in_band_runs, s.in_band_blind, s.sensor_fault_runs);
  }

  auto runs = fmt::output_file((dir / "rigs_runs.tsv").string());
  runs.print(
      "run\tcontroller\tbore\trod\tstroke\tsupply\tKv\tmass\tspring\trest_load\tmode_hz\tleak\t"
      "paper_equivalent_leak\tonset\tsensor_fault\tprogram");
  for (std::size_t c = 0; c < all.size(); ++c) {
    runs.print("\tr{}_{}_{}_delay\tr{}_size\tr{}_blind", c, all[c].label,
               all[c].told ? "told" : "not_told", c, c);
  }
  runs.print("\n");
  for (const auto& r : results) {
    const RunSpec& spec = r.run.spec;
    const auto& p = spec.scenario.params;
    runs.print("{}\t{}\t{:.5g}\t{:.5g}\t{:.5g}\t{:.5g}\t{:.5g}\t{:.5g}\t{:.5g}\t{:.4g}\t{:.4g}\t",
               spec.id, sim::to_string(spec.scenario.controller), p.D, p.d, p.L, p.ps, p.Kv, p.m,
               p.K_s, r.rest_load, r.mode_hz);
    // The program's phases where they start ("hold 0.01 @0; sine 0.5 0.02 @212.4; ..."), or
    // empty for the rig's steps.
    std::string program;
    for (const ProgramPhase& phase : spec.phases) {
      program +=
          fmt::format("{}{} @{:.1f}", program.empty() ? "" : "; ", phase.notation, phase.start);
    }
    runs.print("{:.4g}\t{:.4g}\t{}\t{}\t{}", spec.leak, paper_equivalent_leak(spec),
               spec.leak > 0.0 ? fmt::format("{:.3f}", spec.onset) : std::string(""), r.first_fault,
               program);
    for (std::size_t c = 0; c < all.size(); ++c) {
      // The first raise: its delay after the onset (negative: before it, a false alarm).
      const auto& alarms = r.run.alarms[c][0];
      if (alarms.empty()) {
        runs.print("\t\t\t{}", r.blind[c] ? 1 : 0);
      } else {
        const double reference = spec.leak > 0.0 ? spec.onset : 0.0;
        runs.print("\t{:.3f}\t{:.4g}\t{}", alarms.front().raised - reference,
                   alarms.front().leak_coefficient, r.blind[c] ? 1 : 0);
      }
    }
    runs.print("\n");
  }
}

}  // namespace leakmon::study
