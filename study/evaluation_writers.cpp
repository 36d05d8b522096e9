#include "study/evaluation_writers.hpp"

#include <fmt/format.h>
#include <fmt/os.h>
#include <fmt/ranges.h>

#include <cmath>
#include <string>

#include "study/evaluation_summary.hpp"

namespace leakmon::study {
namespace {

constexpr double kLitresPerMinutePerMPa = 60000.0 * 1e6;  // m^3/(s Pa) -> l/min/MPa

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

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
    const SizeCheck& size = r.size_check;
    f.print(
        "}}, \"size_at_raise\": {{\"t\": {}, \"leak_coefficient\": {}, "
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
                all[c].label, controller, size, size * kLitresPerMinutePerMPa, rates.detected,
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
  // Sensor faults: named on the right channel within 5 s of the fault's start.
  int faults = 0, named = 0, wrong_channel = 0;
  for (const auto& r : results) {
    if (r.spec.fault_channel.empty()) continue;
    ++faults;
    bool found = false;
    for (const auto& a : r.sensor_alarms) {
      if (a.t < r.spec.fault_start || a.t > r.spec.fault_end + 5.0) continue;
      if (a.channel == r.spec.fault_channel && a.t <= r.spec.fault_start + 5.0) found = true;
      if (a.channel != r.spec.fault_channel) ++wrong_channel;
    }
    named += found ? 1 : 0;
  }
  if (faults > 0) {
    const Interval ci = clopper_pearson_95(named, faults);
    f_md.print(
        "\nSensor faults: {}/{} named on the faulty channel within 5 s (95 % interval "
        "{:.0f}-{:.0f} "
        "%); {} sensor_fault alarms on another channel while a fault was present.\n",
        named, faults, 100.0 * ci.lower, 100.0 * ci.upper, wrong_channel);
  }
}

}  // namespace leakmon::study
