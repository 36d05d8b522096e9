#include "study/evaluation_summary.hpp"

#include <algorithm>
#include <cmath>

#include "sim/scenario.hpp"

namespace leakmon::study {
namespace {

// P(X <= k) of a Poisson(mu), summed in logs.
double poisson_cdf(int k, double mu) {
  double sum = 0.0;
  for (int i = 0; i <= k; ++i) {
    sum += std::exp(-mu + i * std::log(mu) - std::lgamma(i + 1.0));
  }
  return sum;
}

// P(X <= k) of a Binomial(n, p), 0 < p < 1.
double binomial_cdf(int k, int n, double p) {
  double sum = 0.0;
  for (int i = 0; i <= k; ++i) {
    sum += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) +
                    i * std::log(p) + (n - i) * std::log1p(-p));
  }
  return sum;
}

// The x in (lo, hi) where the decreasing function f crosses `level`, by bisection.
template <class F>
double solve_decreasing(F f, double level, double lo, double hi) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) > level ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

bool in_group(const RunResult& r, std::string_view controller) {
  return controller == "all" || sim::to_string(r.spec.scenario.controller) == controller;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

double poisson_upper_95(int events) {
  const double hi = events + 20.0 * std::sqrt(events + 1.0) + 20.0;
  return solve_decreasing([&](double mu) { return poisson_cdf(events, mu); }, 0.05, 0.0, hi);
}

Interval clopper_pearson_95(int successes, int trials) {
  if (trials <= 0) return {0.0, 1.0};
  Interval interval{0.0, 1.0};
  // P(X >= k) = 1 - P(X <= k - 1) rises with p; P(X <= k) falls.
  if (successes > 0) {
    interval.lower = solve_decreasing(
        [&](double p) { return binomial_cdf(successes - 1, trials, p); }, 0.975, 0.0, 1.0);
  }
  if (successes < trials) {
    interval.upper = solve_decreasing([&](double p) { return binomial_cdf(successes, trials, p); },
                                      0.025, 0.0, 1.0);
  }
  return interval;
}

double Rates::false_alarms_per_hour() const {
  return healthy_hours > 0 ? false_alarms / healthy_hours : NAN;
}

double Rates::false_alarms_per_hour_upper_95() const {
  return healthy_hours > 0 ? poisson_upper_95(false_alarms) / healthy_hours : NAN;
}

double Rates::detection_rate() const { return leak_runs > 0 ? double(detected) / leak_runs : NAN; }

Interval Rates::detection_rate_95() const { return clopper_pearson_95(detected, leak_runs); }

double Rates::median_delay() const { return median_of(delays); }

double Rates::median_abs_size_error() const {
  std::vector<double> e;
  for (double v : size_errors) e.push_back(std::abs(v));
  return median_of(std::move(e));
}

void add_run(Rates& rates, const RunResult& run, std::size_t candidate, std::size_t threshold,
             double detect_within, bool include_healthy, bool include_leak) {
  const RunSpec& spec = run.spec;
  const double healthy_end = std::min(spec.onset, run.seconds);
  const auto& alarms = run.alarms[candidate][threshold];
  if (include_healthy) {
    double monitored = std::max(0.0, healthy_end - spec.monitor_from);
    // A restart's downtime is no monitored time.
    if (!std::isnan(spec.downtime) && healthy_end > spec.stop_at) {
      monitored -= std::min(spec.downtime, healthy_end - spec.stop_at);
    }
    rates.healthy_hours += monitored / 3600.0;
    for (const auto& a : alarms) {
      if (a.raised < healthy_end) ++rates.false_alarms;
    }
  }
  if (include_leak && spec.leak > 0.0) {
    ++rates.leak_runs;
    for (const auto& a : alarms) {
      if (a.raised < spec.onset) continue;
      const double delay = a.raised - spec.onset;
      if (delay <= detect_within) {
        ++rates.detected;
        rates.delays.push_back(delay);
        if (!std::isnan(a.leak_coefficient)) {
          rates.size_errors.push_back(a.leak_coefficient / spec.leak - 1.0);
        }
      }
      break;
    }
  }
}

Rates rates_of(const std::vector<RunResult>& results, std::size_t candidate, std::size_t threshold,
               std::string_view controller, double leak, double detect_within) {
  Rates rates;
  for (const auto& r : results) {
    if (!in_group(r, controller) || r.spec.sensor_fault_run) continue;
    // A seal that wears is scored by the size it is found at (score_wear), not within a window.
    const bool leak_match = (leak == 0.0 || r.spec.leak == leak) && !r.spec.wear_run();
    add_run(rates, r, candidate, threshold, detect_within, true, leak_match);
  }
  return rates;
}

double Coverage::median_relative_half_width() const {
  return relative_half_widths.empty() ? NAN : relative_half_widths[relative_half_widths.size() / 2];
}

Coverage coverage_of(const std::vector<RunResult>& results, std::string_view controller,
                     double leak) {
  Coverage coverage;
  for (const auto& r : results) {
    if (r.spec.leak != leak || std::isnan(r.size_check.leak_coefficient)) continue;
    if (r.spec.sensor_fault_run || r.spec.wear_run()) continue;
    if (!in_group(r, controller)) continue;
    ++coverage.raised;
    coverage.covered += r.size_check.covers(leak) ? 1 : 0;
    coverage.relative_half_widths.push_back(r.size_check.half_width / leak);
  }
  std::sort(coverage.relative_half_widths.begin(), coverage.relative_half_widths.end());
  return coverage;
}

std::vector<SensorFaultScore> score_sensor_faults(const std::vector<RunResult>& results,
                                                  double detect_within) {
  std::vector<SensorFaultScore> scores;
  const std::size_t t = design_index(candidates()[kSensorCandidate]);
  for (const auto& r : results) {
    const RunSpec& spec = r.spec;
    if (spec.fault_channel.empty()) continue;
    auto found = std::find_if(scores.begin(), scores.end(), [&](const SensorFaultScore& score) {
      return score.variant == spec.fault_variant;
    });
    if (found == scores.end()) {
      SensorFaultScore score;
      score.variant = spec.fault_variant;
      scores.push_back(score);
      found = scores.end() - 1;
    }
    SensorFaultScore& score = *found;
    if (std::isnan(spec.fault_seen)) {
      ++score.never_seen;  // a spikes fault too short for any spike: nothing to name
    } else {
      ++score.runs;
      double first = NAN;
      bool right_kind = false;
      for (const auto& a : r.sensor_alarms) {
        if (a.t < spec.fault_start || a.t > spec.fault_end + kNamedWithinSeconds) continue;
        if (a.channel != spec.fault_channel) {
          ++score.wrong_channel;
          continue;
        }
        if (std::isnan(first)) {
          first = a.t;
          right_kind = a.fault == spec.fault_kind;
        }
      }
      const double latency = first - spec.fault_seen;
      if (!std::isnan(first) && latency <= kNamedWithinSeconds) {
        ++score.named;
        score.right_kind += right_kind ? 1 : 0;
        score.latencies.push_back(latency);
      }
    }
    // internal_leakage while the fault lasts or after it, before any leak has opened.
    for (const auto& a : r.alarms[kSensorCandidate][t]) {
      if (a.raised >= spec.fault_start && a.raised < spec.onset) {
        ++score.leakage_raised;
        break;
      }
    }
    if (spec.leak > 0.0 && spec.onset >= spec.fault_start && spec.onset < spec.fault_end) {
      ++score.leak_runs;
      for (const auto& a : r.alarms[kSensorCandidate][t]) {
        if (a.raised < spec.onset) continue;
        if (a.raised <= spec.fault_end + detect_within) {
          ++score.leak_found;
          score.leak_delays_after_fault.push_back(a.raised - spec.fault_end);
        }
        break;
      }
    }
  }
  std::sort(scores.begin(), scores.end(),
            [](const auto& a, const auto& b) { return a.variant < b.variant; });
  return scores;
}

SensorAlarmsWithoutFault sensor_alarms_without_fault(const std::vector<RunResult>& results) {
  SensorAlarmsWithoutFault out;
  for (const auto& r : results) {
    if (!r.spec.fault_channel.empty()) continue;
    double monitored = r.seconds;
    if (!std::isnan(r.spec.downtime)) monitored -= r.spec.downtime;
    out.hours += monitored / 3600.0;
    out.alarms += static_cast<int>(r.sensor_alarms.size());
  }
  return out;
}

RestartScore score_restarts(const std::vector<RunResult>& results, std::size_t candidate,
                            double detect_within) {
  RestartScore score;
  const std::size_t t = design_index(candidates()[candidate]);
  for (const auto& r : results) {
    const RunSpec& spec = r.spec;
    if (std::isnan(spec.restart_at)) continue;
    score.restored += r.states_restored > 0 ? 1 : 0;
    const auto& alarms = r.alarms[candidate][t];
    for (const auto& a : alarms) {
      if (a.raised >= spec.monitor_from && a.raised < spec.stop_at) {
        ++score.raised_before_stop;
        break;
      }
    }
    const bool warmer = spec.temp_after > spec.temp_before;
    if (spec.leak > 0.0) {
      ++score.leak_runs;
      (warmer ? score.leak_runs_warmer : score.leak_runs_cooler) += 1;
      for (const auto& a : alarms) {
        if (a.raised < spec.restart_at) continue;
        if (a.raised - spec.restart_at <= detect_within) {
          ++score.found;
          (warmer ? score.found_warmer : score.found_cooler) += 1;
          score.delays.push_back(a.raised - spec.restart_at);
        }
        break;
      }
    } else {
      ++score.healthy_runs;
      score.healthy_hours_after += (r.seconds - spec.restart_at) / 3600.0;
      for (const auto& a : alarms) {
        if (a.raised >= spec.restart_at) {
          ++score.healthy_raised;
          break;
        }
      }
    }
  }
  std::sort(score.delays.begin(), score.delays.end());
  return score;
}

double PhaseKindScore::false_alarms_per_hour() const {
  return healthy_hours > 0 ? false_alarms / healthy_hours : NAN;
}

double PhaseKindScore::false_alarms_per_hour_upper_95() const {
  return healthy_hours > 0 ? poisson_upper_95(false_alarms) / healthy_hours : NAN;
}

std::vector<PhaseKindScore> score_program_phases(const std::vector<RunResult>& results,
                                                 std::size_t candidate, double detect_within,
                                                 std::optional<std::size_t> threshold) {
  // Rows: the five kinds with the holds that cannot be judged after the holds.
  std::vector<PhaseKindScore> rows;
  for (const sim::PhaseKind kind : sim::kPhaseKinds) {
    rows.push_back({.phase = std::string(sim::to_string(kind))});
    if (kind == sim::PhaseKind::hold) rows.push_back({.phase = "hold (not judgeable)"});
  }
  auto row_of = [&](const ProgramPhase& phase) -> PhaseKindScore& {
    const std::string name = phase.kind == sim::PhaseKind::hold && !phase.judgeable
                                 ? std::string("hold (not judgeable)")
                                 : std::string(sim::to_string(phase.kind));
    return *std::find_if(rows.begin(), rows.end(),
                         [&](const PhaseKindScore& row) { return row.phase == name; });
  };
  const std::size_t t = threshold.value_or(design_index(candidates()[candidate]));
  for (const auto& r : results) {
    const RunSpec& spec = r.spec;
    if (spec.phases.empty() || spec.sensor_fault_run || spec.wear_run()) continue;
    const double healthy_end = std::min(spec.onset, r.seconds);
    for (const ProgramPhase& phase : spec.phases) {
      const double from = std::max(phase.start, spec.monitor_from);
      const double to = std::min(phase.end, healthy_end);
      if (to > from) row_of(phase).healthy_hours += (to - from) / 3600.0;
    }
    const auto& alarms = r.alarms[candidate][t];
    for (const auto& a : alarms) {
      if (a.raised >= healthy_end) continue;
      const int i = spec.phase_at(a.raised);
      if (i < 0) continue;
      const auto at = static_cast<std::size_t>(i);
      PhaseKindScore& row = row_of(spec.phases[at]);
      ++row.false_alarms;
      if (a.raised - spec.phases[at].start <= kPhaseStartSeconds) {
        ++row.early_false_alarms;
        if (at > 0 && spec.phases[at - 1].kind == sim::PhaseKind::hold) {
          ++row.after_hold_false_alarms;
        }
      }
    }
    if (spec.leak <= 0.0 || spec.leak_phase < 0) continue;
    const ProgramPhase& opened_in = spec.phases[static_cast<std::size_t>(spec.leak_phase)];
    PhaseKindScore& row = row_of(opened_in);
    ++row.leak_runs;
    const double deadline = spec.detection_deadline(detect_within);
    for (const auto& a : alarms) {
      if (a.raised < spec.onset) continue;
      if (a.raised <= deadline) {
        ++row.found;
        row.delays.push_back(a.raised - (opened_in.judgeable ? spec.onset : opened_in.end));
      } else {
        ++row.found_late;
      }
      break;
    }
  }
  return rows;
}

std::vector<ProgramStartScore> score_program_starts(const std::vector<RunResult>& results,
                                                    std::size_t candidate,
                                                    std::optional<std::size_t> threshold) {
  std::vector<ProgramStartScore> rows = {{.starts_with_hold = true}, {.starts_with_hold = false}};
  const std::size_t t = threshold.value_or(design_index(candidates()[candidate]));
  for (const auto& r : results) {
    const RunSpec& spec = r.spec;
    if (spec.phases.empty() || spec.sensor_fault_run || spec.wear_run()) continue;
    ProgramStartScore& row = rows[spec.phases.front().kind == sim::PhaseKind::hold ? 0 : 1];
    const double healthy_end = std::min(spec.onset, r.seconds);
    ++row.runs;
    row.healthy_hours += std::max(0.0, healthy_end - spec.monitor_from) / 3600.0;
    int raised = 0;
    for (const auto& a : r.alarms[candidate][t]) raised += a.raised < healthy_end ? 1 : 0;
    row.false_alarms += raised;
    row.runs_with_false_alarm += raised > 0 ? 1 : 0;
  }
  return rows;
}

std::vector<WearScore> score_wear(const std::vector<RunResult>& results, std::size_t candidate,
                                  std::optional<std::size_t> threshold) {
  std::vector<WearScore> rows = {
      {.growth = "all"}, {.growth = "slow"}, {.growth = "medium"}, {.growth = "fast"}};
  const std::size_t t = threshold.value_or(design_index(candidates()[candidate]));
  for (const auto& r : results) {
    const RunSpec& spec = r.spec;
    if (!spec.wear_run() || spec.leak <= 0.0) continue;
    const double per_hour = spec.leak / spec.valve_scale / (spec.wear_seconds / 3600.0);
    WearScore& band = rows[per_hour < kWearSlow ? 1 : per_hour < kWearFast ? 2 : 3];
    for (WearScore* row : {&rows[0], &band}) {
      ++row->runs;
      for (const auto& a : r.alarms[candidate][t]) {
        if (a.raised < spec.onset) continue;
        const double size = spec.leak_at(a.raised) / spec.valve_scale;
        ++row->found;
        row->found_before_target += size <= kWearTarget ? 1 : 0;
        row->found_at.push_back(size);
        break;
      }
    }
  }
  return rows;
}

}  // namespace leakmon::study
