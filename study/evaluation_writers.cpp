#include "study/evaluation_writers.hpp"

#include <fmt/format.h>
#include <fmt/os.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "capture/units.hpp"
#include "study/evaluation_summary.hpp"

namespace leakmon::study {
namespace {

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

std::string percent_interval(int successes, int trials) {
  if (trials == 0) return "0/0";
  const Interval ci = clopper_pearson_95(successes, trials);
  return fmt::format("{}/{} ({:.1f} %; 95 % CI {:.1f}-{:.1f} %)", successes, trials,
                     trials ? 100.0 * successes / trials : NAN, 100.0 * ci.lower, 100.0 * ci.upper);
}

std::string median_text(std::vector<double> v, const char* unit) {
  if (v.empty()) return "-";
  std::sort(v.begin(), v.end());
  return fmt::format("{:.2f}{}", v[v.size() / 2], unit);
}

// Per fault kind: named on the right channel within 5 s, other channels, internal_leakage, and
// the leak decision after the fault.
void write_sensor_fault_table(fmt::ostream& f, const std::vector<RunResult>& results,
                              double detect_within) {
  const auto scores = score_sensor_faults(results, detect_within);
  if (scores.empty()) return;
  f.print(
      "\nSensor faults (the default detector's actuator; named = a sensor_fault alarm on the "
      "faulty channel within {:.0f} s of the fault showing, spikes: of the first spike):\n\n"
      "| fault | runs | named within {:.0f} s (95 % CI) | kind named right | median latency | "
      "alarms on other channels | internal_leakage raised | leak opened in the fault, found "
      "within {:.0f} s of its end | median delay after the end |\n"
      "|---|---|---|---|---|---|---|---|---|\n",
      kNamedWithinSeconds, kNamedWithinSeconds, detect_within);
  SensorFaultScore total;
  total.variant = "all";
  for (const auto& score : scores) {
    total.runs += score.runs;
    total.never_seen += score.never_seen;
    total.named += score.named;
    total.right_kind += score.right_kind;
    total.wrong_channel += score.wrong_channel;
    total.leakage_raised += score.leakage_raised;
    total.leak_runs += score.leak_runs;
    total.leak_found += score.leak_found;
    total.latencies.insert(total.latencies.end(), score.latencies.begin(), score.latencies.end());
    total.leak_delays_after_fault.insert(total.leak_delays_after_fault.end(),
                                         score.leak_delays_after_fault.begin(),
                                         score.leak_delays_after_fault.end());
  }
  auto row = [&](const SensorFaultScore& score) {
    f.print("| {} | {}{} | {} | {}/{} | {} | {} | {}/{} | {}/{} | {} |\n", score.variant,
            score.runs,
            score.never_seen ? fmt::format(" (+{} without a spike)", score.never_seen) : "",
            percent_interval(score.named, score.runs), score.right_kind, score.named,
            median_text(score.latencies, " s"), score.wrong_channel, score.leakage_raised,
            score.runs + score.never_seen, score.leak_found, score.leak_runs,
            median_text(score.leak_delays_after_fault, " s"));
  };
  for (const auto& score : scores) row(score);
  row(total);
  const SensorAlarmsWithoutFault clean = sensor_alarms_without_fault(results);
  f.print("\nsensor_fault alarms in runs without a fault: {} in {:.1f} monitored h.\n",
          clean.alarms, clean.hours);
}

// Restarts: leaks that opened while the daemon was down found within the window of the
// restart; healthy restarts that raised internal_leakage.
void write_restart_table(fmt::ostream& f, const std::vector<RunResult>& results,
                         double detect_within) {
  const auto all = candidates();
  bool any = false;
  for (const auto& r : results) any = any || !std::isnan(r.spec.restart_at);
  if (!any) return;
  f.print(
      "\nRestarts (design thresholds; the leak opened while the daemon was down):\n\n"
      "| detector | leak found within {:.0f} s of the restart (95 % CI) | oil warmer / cooler | "
      "median delay | healthy restarts raising internal_leakage (95 % CI) | healthy h after "
      "restarts | raised before the stop | state resumed |\n"
      "|---|---|---|---|---|---|---|---|\n",
      detect_within);
  for (std::size_t c = 0; c < all.size(); ++c) {
    const RestartScore score = score_restarts(results, c, detect_within);
    f.print("| {} | {} | {}/{} / {}/{} | {} | {} | {:.1f} | {} | {}/{} |\n", all[c].label,
            percent_interval(score.found, score.leak_runs), score.found_warmer,
            score.leak_runs_warmer, score.found_cooler, score.leak_runs_cooler,
            median_text(score.delays, " s"),
            percent_interval(score.healthy_raised, score.healthy_runs), score.healthy_hours_after,
            score.raised_before_stop, score.restored, score.leak_runs + score.healthy_runs);
  }
}

// Test programs per phase kind, and split by how the program starts: conditions.md and
// programs.tsv.
void write_program_tables(fmt::ostream& f, const std::filesystem::path& dir,
                          const std::vector<RunResult>& results, double detect_within) {
  bool any = false;
  for (const auto& r : results) any = any || !r.spec.phases.empty();
  if (!any) return;
  const auto all = candidates();
  auto tsv = fmt::output_file((dir / "programs.tsv").string());
  tsv.print(
      "detector\tphase\thealthy_hours\tfalse_alarms\tfa_per_hour\tfa_upper_95\t"
      "fa_first_{0:.0f}s\tfa_first_{0:.0f}s_after_hold\tleak_runs\tfound\tfound_late\t"
      "median_delay\n",
      kPhaseStartSeconds);
  f.print(
      "\nTest programs per phase kind (design thresholds). Healthy time: monitored, before any "
      "onset, in phases of the kind; a false alarm counts in the phase it was raised in. A leak "
      "counts in the phase it opened in and is found when raised within {0:.0f} s of its onset, "
      "or, in a hold whose |K_s X| / A stays below {1:g} MPa (not judgeable), within {0:.0f} s "
      "of the next phase's start (the delay is then counted from that start).\n\n"
      "| detector | phase | healthy h | false alarms / h (count; 95 % upper bound) | of them in "
      "the phase's first {2:.0f} s (after a hold) | leaks found in time (95 % CI) | found later "
      "| median delay |\n|---|---|---|---|---|---|---|---|\n",
      detect_within, kJudgeableLoad / 1e6, kPhaseStartSeconds);
  for (std::size_t c = 0; c < all.size(); ++c) {
    for (const PhaseKindScore& row : score_program_phases(results, c, detect_within)) {
      f.print("| {} | {} | {:.2f} | {:.2f} ({}; <= {:.2f}) | {} ({}) | {} | {} | {} |\n",
              all[c].label, row.phase, row.healthy_hours, row.false_alarms_per_hour(),
              row.false_alarms, row.false_alarms_per_hour_upper_95(), row.early_false_alarms,
              row.after_hold_false_alarms, percent_interval(row.found, row.leak_runs),
              row.found_late, median_text(row.delays, " s"));
      std::vector<double> delays = row.delays;
      std::sort(delays.begin(), delays.end());
      tsv.print("{}\t{}\t{:.4g}\t{}\t{:.4g}\t{:.4g}\t{}\t{}\t{}\t{}\t{}\t{:.4g}\n", all[c].label,
                row.phase, row.healthy_hours, row.false_alarms, row.false_alarms_per_hour(),
                row.false_alarms_per_hour_upper_95(), row.early_false_alarms,
                row.after_hold_false_alarms, row.leak_runs, row.found, row.found_late,
                delays.empty() ? NAN : delays[delays.size() / 2]);
    }
  }
  f.print(
      "\nTest programs by how they start (design thresholds; healthy time and false alarms of "
      "the program runs):\n\n| detector | program starts with | runs | healthy h | false alarms "
      "/ h (count; 95 % upper bound) | runs with a false alarm |\n|---|---|---|---|---|---|\n");
  for (std::size_t c = 0; c < all.size(); ++c) {
    for (const ProgramStartScore& row : score_program_starts(results, c)) {
      const double hours = row.healthy_hours;
      f.print("| {} | {} | {} | {:.2f} | {:.2f} ({}; <= {:.2f}) | {} |\n", all[c].label,
              row.starts_with_hold ? "a hold" : "another phase", row.runs, hours,
              hours > 0 ? row.false_alarms / hours : NAN, row.false_alarms,
              hours > 0 ? poisson_upper_95(row.false_alarms) / hours : NAN,
              row.runs_with_false_alarm);
    }
  }
}

// Seals that wear: the C_L at which each candidate finds them, and whether before kWearTarget,
// per growth rate: conditions.md and wear.tsv.
void write_wear_table(fmt::ostream& f, const std::filesystem::path& dir,
                      const std::vector<RunResult>& results) {
  bool any = false;
  for (const auto& r : results) any = any || (r.spec.wear_run() && r.spec.leak > 0.0);
  if (!any) return;
  const auto all = candidates();
  auto tsv = fmt::output_file((dir / "wear.tsv").string());
  tsv.print("detector\tgrowth\truns\tfound\tfound_before_target\tmedian_found_at\n");
  f.print(
      "\nSeals that wear (design thresholds; C_L from 0 to 1e-12..5e-12 over 10 min to 4 h; found "
      "= the first raise after the wear began, with the C_L in force then; growth = final C_L / "
      "wear time, slow < {:g}, fast >= {:g} m^3/(s Pa) per hour):\n\n"
      "| detector | found | found before C_L = {:g} (95 % CI) | median C_L when found | slow: "
      "before {:g} | medium | fast |\n|---|---|---|---|---|---|---|\n",
      kWearSlow, kWearFast, kWearTarget, kWearTarget);
  for (std::size_t c = 0; c < all.size(); ++c) {
    const std::vector<WearScore> rows = score_wear(results, c);
    auto median_size = [](std::vector<double> v) {
      if (v.empty()) return std::string("-");
      std::sort(v.begin(), v.end());
      return fmt::format("{:.2g}", v[v.size() / 2]);
    };
    f.print("| {} | {}/{} | {} | {} | {}/{} | {}/{} | {}/{} |\n", all[c].label, rows[0].found,
            rows[0].runs, percent_interval(rows[0].found_before_target, rows[0].runs),
            median_size(rows[0].found_at), rows[1].found_before_target, rows[1].runs,
            rows[2].found_before_target, rows[2].runs, rows[3].found_before_target, rows[3].runs);
    for (const WearScore& row : rows) {
      std::vector<double> sizes = row.found_at;
      std::sort(sizes.begin(), sizes.end());
      tsv.print("{}\t{}\t{}\t{}\t{}\t{:.4g}\n", all[c].label, row.growth, row.runs, row.found,
                row.found_before_target, sizes.empty() ? NAN : sizes[sizes.size() / 2]);
    }
  }
}

}  // namespace

void write_runs_json(const std::filesystem::path& path, const std::vector<RunResult>& results) {
  const auto all = candidates();
  auto f = fmt::output_file(path.string());
  f.print("[\n");
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& r = results[i];
    const auto& s = r.spec.scenario;
    f.print(
        "  {{\"id\": {}, \"controller\": \"{}\", \"seconds\": {}, \"leak\": {}, "
        "\"onset\": {}, \"K_s\": {}, \"beta\": {}, \"Kv\": {}, \"m\": {}, \"b\": {}, "
        "\"amp_max\": {}, \"operating\": \"{}\", \"alarms\": {{",
        r.spec.id, sim::to_string(s.controller), json_number(r.seconds), json_number(r.spec.leak),
        json_number(r.spec.leak > 0 ? r.spec.onset : NAN), json_number(s.params.K_s),
        json_number(s.params.beta), json_number(s.params.Kv), json_number(s.params.m),
        json_number(s.params.b), json_number(s.reference.amp_max), r.spec.condition.operating);
    for (std::size_t c = 0; c < all.size(); ++c) {
      f.print("{}\"{}\": [", c ? ", " : "", all[c].label);
      const auto& alarms = r.alarms[c][design_index(all[c])];
      for (std::size_t a = 0; a < alarms.size(); ++a) {
        f.print("{}{{\"t\": {}, \"leak_coefficient\": {}}}", a ? ", " : "",
                json_number(alarms[a].raised), json_number(alarms[a].leak_coefficient));
      }
      f.print("]");
    }
    f.print("}}");
    if (!r.spec.fault_channel.empty()) {
      f.print(
          ", \"fault\": {{\"channel\": \"{}\", \"kind\": \"{}\", \"variant\": \"{}\", "
          "\"start\": {}, \"duration\": {}, \"seen\": {}}}",
          r.spec.fault_channel, r.spec.fault_kind, r.spec.fault_variant,
          json_number(r.spec.fault_start), json_number(r.spec.fault_end - r.spec.fault_start),
          json_number(r.spec.fault_seen));
    }
    f.print(", \"sensor_fault_alarms\": [");
    for (std::size_t a = 0; a < r.sensor_alarms.size(); ++a) {
      const auto& alarm = r.sensor_alarms[a];
      f.print("{}{{\"t\": {}, \"channel\": \"{}\", \"kind\": \"{}\"}}", a ? ", " : "",
              json_number(alarm.t), alarm.channel, alarm.fault);
    }
    f.print("]");
    if (!std::isnan(r.spec.restart_at)) {
      f.print(
          ", \"restart\": {{\"stop\": {}, \"downtime\": {}, \"restart\": {}, "
          "\"temp_before\": {}, \"temp_after\": {}, \"states_restored\": {}}}",
          json_number(r.spec.stop_at), json_number(r.spec.downtime), json_number(r.spec.restart_at),
          json_number(r.spec.temp_before), json_number(r.spec.temp_after), r.states_restored);
    }
    if (!r.spec.phases.empty()) {
      f.print(", \"program\": [");
      for (std::size_t p = 0; p < r.spec.phases.size(); ++p) {
        const ProgramPhase& phase = r.spec.phases[p];
        f.print("{}{{\"phase\": \"{}\", \"start\": {}, \"end\": {}, \"judgeable\": {}}}",
                p ? ", " : "", phase.notation, json_number(phase.start), json_number(phase.end),
                phase.judgeable ? "true" : "false");
      }
      f.print("], \"leak_phase\": {}",
              r.spec.leak_phase >= 0 ? fmt::format("{}", r.spec.leak_phase) : "null");
    }
    if (r.spec.wear_run()) {
      f.print(", \"wear_seconds\": {}", json_number(r.spec.wear_seconds));
    }
    const SizeCheck& size = r.size_check;
    f.print(
        ", \"size_at_raise\": {{\"t\": {}, \"leak_coefficient\": {}, "
        "\"half_width_95\": {}}}}}{}\n",
        json_number(size.t), json_number(size.leak_coefficient), json_number(size.half_width),
        i + 1 < results.size() ? "," : "");
  }
  f.print("]\n");
}

void write_summaries(const std::filesystem::path& dir, const EvaluationOptions& options,
                     const std::vector<RunResult>& results) {
  const auto all = candidates();
  auto f_json = fmt::output_file((dir / "summary.json").string());
  auto f_tsv = fmt::output_file((dir / "summary.tsv").string());
  auto f_md = fmt::output_file((dir / "summary.md").string());
  auto f_tsv_coverage = fmt::output_file((dir / "size_coverage.tsv").string());
  f_tsv_coverage.print("controller\tleak\traised\tcovered\tmedian_relative_half_width\n");
  f_tsv.print(
      "detector\tcontroller\tleak\tthreshold\tdesign\tfa_per_hour\thealthy_hours\t"
      "detected\tleak_runs\tdetection_rate\tmedian_delay\tmedian_abs_size_error\n");
  f_md.print(
      "| detector | controller | C_L [m^3/(s Pa)] | l/min/MPa | detected within {:.0f} s | "
      "median delay [s] | false alarms / h (healthy h) | median size error |\n"
      "|---|---|---|---|---|---|---|---|\n",
      options.detect_within);
  f_json.print(
      "{{\n  \"settings\": {{\"healthy_runs\": {}, \"healthy_seconds\": {}, "
      "\"runs_per_leak\": {}, \"learn_seconds\": {}, \"seed\": {}, "
      "\"detect_within\": {}, \"effects\": \"{}\"}},\n  \"detectors\": [\n",
      options.healthy_runs, options.healthy_seconds, options.runs_per_leak, options.learn_seconds,
      options.seed, options.detect_within, fmt::join(options.effects, ","));
  for (std::size_t c = 0; c < all.size(); ++c) {
    f_json.print(
        "    {{\"name\": \"{}\", \"kind\": \"{}\", \"design_threshold\": {}, \"rows\": [\n",
        all[c].label, all[c].kind, all[c].design_threshold);
    bool first_row = true;
    for (std::size_t t = 0; t < all[c].raise_thresholds.size(); ++t) {
      const double threshold = all[c].raise_thresholds[t];
      const bool design = threshold == all[c].design_threshold;
      for (const auto controller : kControllerGroups) {
        std::vector<double> sizes = {0.0};  // 0: all leak sizes pooled
        sizes.insert(sizes.end(), options.leak_sizes.begin(), options.leak_sizes.end());
        for (double size : sizes) {
          const Rates rates = rates_of(results, c, t, controller, size, options.detect_within);
          f_tsv.print("{}\t{}\t{:g}\t{:g}\t{}\t{:.4g}\t{:.4g}\t{}\t{}\t{:.4g}\t{:.4g}\t{:.4g}\n",
                      all[c].label, controller, size, threshold, design ? 1 : 0,
                      rates.false_alarms_per_hour(), rates.healthy_hours, rates.detected,
                      rates.leak_runs, rates.detection_rate(), rates.median_delay(),
                      rates.median_abs_size_error());
          f_json.print(
              "{}      {{\"controller\": \"{}\", \"leak\": {}, \"threshold\": {}, "
              "\"design\": {}, \"false_alarms\": {}, \"healthy_hours\": {}, "
              "\"false_alarms_per_hour\": {}, \"leak_runs\": {}, \"detected\": {}, "
              "\"detection_rate\": {}, \"median_delay\": {}, \"delays\": [{}], "
              "\"median_abs_size_error\": {}}}",
              first_row ? "" : ",\n", controller, json_number(size), threshold,
              design ? "true" : "false", rates.false_alarms, json_number(rates.healthy_hours),
              json_number(rates.false_alarms_per_hour()), rates.leak_runs, rates.detected,
              json_number(rates.detection_rate()), json_number(rates.median_delay()),
              fmt::join(rates.delays, ", "), json_number(rates.median_abs_size_error()));
          first_row = false;
          if (design && size > 0.0) {
            f_md.print(
                "| {} | {} | {:.2g} | {:.3f} | {}/{} ({:.0f} %) | {} | {:.2f} ({:.1f}) | {} |\n",
                all[c].label, controller, size, units::lpm_per_mpa(size), rates.detected,
                rates.leak_runs, 100.0 * rates.detection_rate(),
                std::isnan(rates.median_delay()) ? std::string("-")
                                                 : fmt::format("{:.1f}", rates.median_delay()),
                rates.false_alarms_per_hour(), rates.healthy_hours,
                rates.size_errors.empty()
                    ? std::string("-")
                    : fmt::format("{:.0f} %", 100.0 * rates.median_abs_size_error()));
          }
        }
      }
    }
    f_json.print("\n    ]}}{}\n", c + 1 < all.size() ? "," : "");
  }
  f_json.print("  ]\n}}\n");
  f_json.close();
  f_tsv.close();
  // How often the flow balance's 95 % interval at its first raise covers the true C_L.
  f_md.print(
      "\n| controller | C_L [m^3/(s Pa)] | raised within {:.0f} s | interval covers truth | "
      "median half-width / C_L |\n|---|---|---|---|---|\n",
      options.detect_within);
  for (const auto controller : kControllerGroups) {
    for (double size : options.leak_sizes) {
      const Coverage coverage = coverage_of(results, controller, size);
      const double median_width = coverage.median_relative_half_width();
      f_md.print("| {} | {:.2g} | {} | {}/{} | {} |\n", controller, size, coverage.raised,
                 coverage.covered, coverage.raised,
                 coverage.relative_half_widths.empty()
                     ? std::string("-")
                     : fmt::format("{:.0f} %", 100.0 * median_width));
      f_tsv_coverage.print("{}\t{:g}\t{}\t{}\t{:.4g}\n", controller, size, coverage.raised,
                           coverage.covered, median_width);
    }
  }
  f_md.close();
  f_tsv_coverage.close();
}

void write_condition_summaries(const std::filesystem::path& dir, const EvaluationOptions& options,
                               const std::vector<RunResult>& results) {
  const auto all = candidates();
  // Written below only when the runs have programs or wear: none left from an earlier run.
  std::filesystem::remove(dir / "programs.tsv");
  std::filesystem::remove(dir / "wear.tsv");
  auto f_md = fmt::output_file((dir / "conditions.md").string());
  auto f_tsv = fmt::output_file((dir / "conditions.tsv").string());
  f_tsv.print(
      "condition\tdetector\tleak\tfalse_alarms\thealthy_hours\tfa_per_hour\tfa_upper_95\t"
      "detected\tleak_runs\tmedian_delay\n");
  f_md.print(
      "| condition | detector | false alarms / h (count in healthy h; 95 % upper bound) | {} |\n"
      "|---|---|---|{}\n",
      fmt::join(options.leak_sizes, " | "), [&] {
        std::string columns;
        for (std::size_t i = 0; i < options.leak_sizes.size(); ++i) columns += "---|";
        return columns;
      }());
  for (const auto& condition : options.conditions) {
    std::vector<RunResult> subset;
    for (const auto& r : results) {
      if (r.spec.condition.operating == condition) subset.push_back(r);
    }
    for (std::size_t c = 0; c < all.size(); ++c) {
      const std::size_t t = design_index(all[c]);
      const Rates healthy = rates_of(subset, c, t, "all", 0.0, options.detect_within);
      f_md.print("| {} | {} | {:.2f} ({} in {:.1f} h; <= {:.2f}) |", condition, all[c].label,
                 healthy.false_alarms_per_hour(), healthy.false_alarms, healthy.healthy_hours,
                 healthy.false_alarms_per_hour_upper_95());
      for (double size : options.leak_sizes) {
        const Rates rates = rates_of(subset, c, t, "all", size, options.detect_within);
        f_md.print(
            " {}/{}{} |", rates.detected, rates.leak_runs,
            rates.delays.empty() ? std::string() : fmt::format(", {:.1f} s", rates.median_delay()));
        f_tsv.print("{}\t{}\t{:g}\t{}\t{:.4g}\t{:.4g}\t{:.4g}\t{}\t{}\t{:.4g}\n", condition,
                    all[c].label, size, healthy.false_alarms, healthy.healthy_hours,
                    healthy.false_alarms_per_hour(), healthy.false_alarms_per_hour_upper_95(),
                    rates.detected, rates.leak_runs, rates.median_delay());
      }
      f_md.print("\n");
    }
  }
  write_sensor_fault_table(f_md, results, options.detect_within);
  write_restart_table(f_md, results, options.detect_within);
  write_program_tables(f_md, dir, results, options.detect_within);
  write_wear_table(f_md, dir, results);
}

}  // namespace leakmon::study
