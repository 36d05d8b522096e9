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
    rates.healthy_hours += std::max(0.0, healthy_end - spec.monitor_from) / 3600.0;
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
    if (!in_group(r, controller)) continue;
    const bool leak_match = leak == 0.0 || r.spec.leak == leak;
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
    if (!in_group(r, controller)) continue;
    ++coverage.raised;
    coverage.covered += r.size_check.covers(leak) ? 1 : 0;
    coverage.relative_half_widths.push_back(r.size_check.half_width / leak);
  }
  std::sort(coverage.relative_half_widths.begin(), coverage.relative_half_widths.end());
  return coverage;
}

}  // namespace leakmon::study
