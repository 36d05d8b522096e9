// The evaluation's statistics over run records: per candidate and threshold, false alarms per
// hour of healthy time, detection probability and delays within the window, the error of the
// size the raising alarm carries, and how often the flow balance's 95 % interval covers the
// true leak size. Confidence bounds for counts come with them.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
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

// Sensor faults per kind and variant (frozen, saturated_high/_low, spikes, dropout_zero/_gap),
// for every run with a fault, scored on the daemon's default actuator at its design threshold
// (kSensorCandidate): named when a sensor_fault alarm on the faulty channel comes within
// kNamedWithinSeconds of the fault showing (its start; spikes: the first spike).
inline constexpr double kNamedWithinSeconds = 5.0;
struct SensorFaultScore {
  std::string variant;
  int runs = 0;            // faults that showed
  int never_seen = 0;      // spikes faults without a single spike in their time
  int named = 0;           // on the right channel within kNamedWithinSeconds
  int right_kind = 0;      // of those, with the injected kind as the first fault named
  int wrong_channel = 0;   // sensor_fault alarms on other channels during the fault (+5 s)
  int leakage_raised = 0;  // runs with internal_leakage from the fault's start on, before any leak
  int leak_runs = 0;       // runs whose leak opened during the fault
  int leak_found = 0;      // ... found after its onset and within detect_within of the fault's end
  std::vector<double> latencies;                // naming after the fault showed [s]
  std::vector<double> leak_delays_after_fault;  // raise - fault end [s] (negative: during it)
};
std::vector<SensorFaultScore> score_sensor_faults(const std::vector<RunResult>& results,
                                                  double detect_within);

// sensor_fault alarms in runs without a fault, over their monitored time.
struct SensorAlarmsWithoutFault {
  int alarms = 0;
  double hours = 0.0;
};
SensorAlarmsWithoutFault sensor_alarms_without_fault(const std::vector<RunResult>& results);

// Restart runs of one candidate at its design threshold: leaks that opened during the downtime
// found within detect_within of the restart, and healthy restarts that raised internal_leakage
// after the restart.
struct RestartScore {
  int leak_runs = 0, found = 0;
  int leak_runs_warmer = 0, found_warmer = 0, leak_runs_cooler = 0, found_cooler = 0;
  std::vector<double> delays;  // after the restart, ascending
  int healthy_runs = 0, healthy_raised = 0;
  double healthy_hours_after = 0.0;
  int raised_before_stop = 0;  // runs with internal_leakage before the daemon stopped (healthy)
  int restored = 0;            // runs in which the restarted replay resumed saved state
};
RestartScore score_restarts(const std::vector<RunResult>& results, std::size_t candidate,
                            double detect_within);

// Test programs (the `programs` condition), one candidate at its design threshold, per phase
// kind: holds whose load |K_s X| / A stays below kJudgeableLoad are a row of their own. Healthy
// time is the monitored time before any onset that the runs spent in phases of the kind; a false
// alarm belongs to the phase it was raised in. A leak belongs to the phase it opened in and is
// found when raised by RunSpec::detection_deadline.
inline constexpr double kPhaseStartSeconds = 30.0;  // "just after a program change"
struct PhaseKindScore {
  std::string phase;  // "steps", "hold", "hold (not judgeable)", "sine", "sweep", "triangle"
  double healthy_hours = 0.0;
  int false_alarms = 0;
  int early_false_alarms = 0;       // within kPhaseStartSeconds of the phase's start
  int after_hold_false_alarms = 0;  // ... of those, in a phase that follows a hold
  int leak_runs = 0;
  int found = 0;       // raised by the deadline
  int found_late = 0;  // raised first after the deadline, before the run's end
  // Of the leaks found: raise - onset, or raise - the next phase's start for a phase that
  // cannot be judged.
  std::vector<double> delays = {};
  double false_alarms_per_hour() const;
  double false_alarms_per_hour_upper_95() const;  // NaN without healthy time
};
// `threshold`: the index into a run's alarms of the candidate (its design threshold's when
// absent; the rig evaluation's runs hold one list per candidate).
std::vector<PhaseKindScore> score_program_phases(const std::vector<RunResult>& results,
                                                 std::size_t candidate, double detect_within,
                                                 std::optional<std::size_t> threshold = {});

// Program runs split by how the program starts (with a hold or not): their healthy time and
// false alarms, for one candidate at its design threshold.
struct ProgramStartScore {
  bool starts_with_hold = false;
  int runs = 0, runs_with_false_alarm = 0;
  double healthy_hours = 0.0;
  int false_alarms = 0;
};
std::vector<ProgramStartScore> score_program_starts(const std::vector<RunResult>& results,
                                                    std::size_t candidate,
                                                    std::optional<std::size_t> threshold = {});

// Seals that wear (the `wear` condition), one candidate at its design threshold: the C_L in force
// at the first raise after the onset, and whether that came before C_L passed kWearTarget.
// Grouped by growth rate C_L / wear time: slow (below kWearSlow per hour), medium, fast (at or
// above kWearFast per hour), and all. Sizes and rates are the paper's valve's equivalent
// (C_L / RunSpec::valve_scale), so another rig's wear is judged as the same share of its flow.
inline constexpr double kWearTarget = 1.5e-12;  // m^3/(s Pa)
inline constexpr double kWearSlow = 1e-12;      // m^3/(s Pa) per hour
inline constexpr double kWearFast = 1e-11;      // m^3/(s Pa) per hour
struct WearScore {
  std::string growth;  // "all", "slow", "medium", "fast"
  int runs = 0, found = 0, found_before_target = 0;
  std::vector<double> found_at = {};  // C_L at the first raise after the onset [m^3/(s Pa)]
};
std::vector<WearScore> score_wear(const std::vector<RunResult>& results, std::size_t candidate,
                                  std::optional<std::size_t> threshold = {});

// The controller groups the summaries report: "all" and each controller.
inline constexpr std::array<std::string_view, 3> kControllerGroups = {"all", "basic",
                                                                      "fault_tolerant"};

}  // namespace leakmon::study
