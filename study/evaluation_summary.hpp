// The evaluation's statistics over run records: per candidate and threshold, false alarms per
// hour of healthy time, detection probability and delays within the window, the error of the
// size the raising alarm carries, and how often the flow balance's 95 % interval covers the
// true leak size. Confidence bounds for counts come with them.
#pragma once

#include <array>
#include <cstddef>
#include <string_view>
#include <vector>

#include "study/evaluation_options.hpp"
#include "study/evaluation_runner.hpp"

namespace leakmon::study {

// Exact one-sided 95 % upper bound of a Poisson mean given `events` observed (Garwood:
// chi2.ppf(0.95, 2 events + 2) / 2; 3.00 for none).
double poisson_upper_95(int events);

struct Interval {
  double lower, upper;
};
// Exact two-sided 95 % (Clopper-Pearson) interval of a binomial probability, `successes` of
// `trials`; [0, 1] for no trials.
Interval clopper_pearson_95(int successes, int trials);

// Error rates of one candidate at one threshold over a set of runs.
struct Rates {
  double healthy_hours = 0.0;
  int false_alarms = 0;
  int leak_runs = 0, detected = 0;
  std::vector<double> delays;       // of runs detected within the window
  std::vector<double> size_errors;  // relative error of the size in the raising alarm
  double false_alarms_per_hour() const;
  double false_alarms_per_hour_upper_95() const;  // NaN without healthy time
  double detection_rate() const;
  Interval detection_rate_95() const;
  double median_delay() const;
  double median_abs_size_error() const;
};

// Healthy time is everything monitored before the onset; a raise there is a false alarm. A leak
// counts as detected if an alarm is raised within `detect_within` seconds of the onset.
void add_run(Rates& rates, const RunResult& run, std::size_t candidate, std::size_t threshold,
             double detect_within, bool include_healthy, bool include_leak);

// Rates of candidate c at threshold t over the runs of `controller` ("all", "basic",
// "fault_tolerant"): healthy time of all of them, leak runs of size `leak` (0: every size).
Rates rates_of(const std::vector<RunResult>& results, std::size_t candidate, std::size_t threshold,
               std::string_view controller, double leak, double detect_within);

// How often the flow balance's interval at its first raise covers the true C_L.
struct Coverage {
  int raised = 0, covered = 0;
  std::vector<double> relative_half_widths;   // half-width / C_L, ascending
  double median_relative_half_width() const;  // NaN when none raised
};
Coverage coverage_of(const std::vector<RunResult>& results, std::string_view controller,
                     double leak);

// The controller groups the summaries report: "all" and each controller.
inline constexpr std::array<std::string_view, 3> kControllerGroups = {"all", "basic",
                                                                      "fault_tolerant"};

}  // namespace leakmon::study
