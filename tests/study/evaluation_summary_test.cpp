// The evaluation's aggregation on hand-built run records (no simulation): false alarms only in
// monitored healthy time, detection only within the window, delays and sizes of the first raise
// after the onset, interval coverage, and the exact confidence bounds against scipy's values.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "study/evaluation_summary.hpp"

namespace leakmon::study {
namespace {

// scipy.stats: chi2.ppf(0.95, 2k + 2) / 2 and beta.ppf(0.025, k, n - k + 1),
// beta.ppf(0.975, k + 1, n - k).
TEST(EvaluationBounds, PoissonUpperBoundMatchesGarwood) {
  EXPECT_NEAR(poisson_upper_95(0), 2.9957322735539895, 1e-9);
  EXPECT_NEAR(poisson_upper_95(1), 4.743864518390577, 1e-9);
  EXPECT_NEAR(poisson_upper_95(3), 7.753656527932725, 1e-9);
  EXPECT_NEAR(poisson_upper_95(10), 16.962219235721903, 1e-9);
}

TEST(EvaluationBounds, ClopperPearsonMatchesBetaQuantiles) {
  struct Case {
    int k, n;
    double lower, upper;
  };
  const Case cases[] = {{0, 10, 0.0, 0.3084971078187608},
                        {10, 10, 0.6915028921812392, 1.0},
                        {5, 10, 0.18708602844739855, 0.8129139715526015},
                        {2, 6, 0.043271868292741676, 0.7772219044964879},
                        {19, 20, 0.7512672372279722, 0.9987349105020502}};
  for (const Case& c : cases) {
    const Interval i = clopper_pearson_95(c.k, c.n);
    EXPECT_NEAR(i.lower, c.lower, 1e-9) << c.k << "/" << c.n;
    EXPECT_NEAR(i.upper, c.upper, 1e-9) << c.k << "/" << c.n;
  }
  const Interval none = clopper_pearson_95(0, 0);
  EXPECT_EQ(none.lower, 0.0);
  EXPECT_EQ(none.upper, 1.0);
}

// One candidate with one threshold; monitoring from 100 s.
RunResult record(int id, sim::ControllerKind controller, double seconds, double leak, double onset,
                 std::vector<Alarm> alarms, SizeCheck size = {}) {
  RunResult r;
  r.spec.id = id;
  r.spec.scenario.controller = controller;
  r.spec.leak = leak;
  r.spec.onset = onset;
  r.spec.monitor_from = 100.0;
  r.seconds = seconds;
  r.alarms = {{std::move(alarms)}};
  r.size_check = size;
  return r;
}

std::vector<RunResult> records() {
  using sim::ControllerKind;
  return {
      // Healthy 1900 s (0.5 h monitored), one false alarm.
      record(0, ControllerKind::basic, 1900.0, 0.0, 1e300, {{500.0, NAN}}),
      // Leak 1e-12 at 280 s: a false alarm before the onset, then raised 10 s after it with a
      // size 20 % high; the interval covers the truth.
      record(1, ControllerKind::fault_tolerant, 400.0, 1e-12, 280.0,
             {{200.0, NAN}, {290.0, 1.2e-12}}, {290.0, 1.2e-12, 0.5e-12}),
      // Leak 1e-12 at 280 s raised only 70 s after the onset: missed (window 60 s); the
      // flow balance raised in time but its interval misses the truth.
      record(2, ControllerKind::basic, 400.0, 1e-12, 280.0, {{350.0, 1e-12}},
             {300.0, 2e-12, 0.5e-12}),
      // Leak 2e-12 at 280 s, raised after 30 s without a size.
      record(3, ControllerKind::basic, 400.0, 2e-12, 280.0, {{310.0, NAN}}),
  };
}

TEST(EvaluationRates, CountsFalseAlarmsDetectionsAndDelays) {
  const auto results = records();
  const Rates all = rates_of(results, 0, 0, "all", 0.0, 60.0);
  // Healthy time: 0.5 h + 3 x 180 s.
  EXPECT_NEAR(all.healthy_hours, 0.5 + 3 * 180.0 / 3600.0, 1e-12);
  EXPECT_EQ(all.false_alarms, 2);
  EXPECT_NEAR(all.false_alarms_per_hour(), 2 / 0.65, 1e-12);
  EXPECT_NEAR(all.false_alarms_per_hour_upper_95(), poisson_upper_95(2) / 0.65, 1e-12);
  EXPECT_EQ(all.leak_runs, 3);
  EXPECT_EQ(all.detected, 2);
  EXPECT_NEAR(all.detection_rate(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(all.median_delay(), 30.0, 1e-9);  // delays 10 and 30: the upper middle
  ASSERT_EQ(all.size_errors.size(), 1u);
  EXPECT_NEAR(all.median_abs_size_error(), 0.2, 1e-9);
  EXPECT_NEAR(all.detection_rate_95().upper, clopper_pearson_95(2, 3).upper, 1e-15);

  // One leak size: healthy time still from every run, leak runs of that size only.
  const Rates small = rates_of(results, 0, 0, "all", 1e-12, 60.0);
  EXPECT_EQ(small.false_alarms, 2);
  EXPECT_EQ(small.leak_runs, 2);
  EXPECT_EQ(small.detected, 1);
  EXPECT_NEAR(small.median_delay(), 10.0, 1e-9);

  // One controller.
  const Rates basic = rates_of(results, 0, 0, "basic", 0.0, 60.0);
  EXPECT_EQ(basic.false_alarms, 1);
  EXPECT_EQ(basic.leak_runs, 2);
  EXPECT_EQ(basic.detected, 1);

  // A wider window turns the late raise into a detection.
  EXPECT_EQ(rates_of(results, 0, 0, "all", 0.0, 90.0).detected, 3);
}

TEST(EvaluationRates, NothingToCountGivesNaN) {
  const Rates none;
  EXPECT_TRUE(std::isnan(none.false_alarms_per_hour()));
  EXPECT_TRUE(std::isnan(none.false_alarms_per_hour_upper_95()));
  EXPECT_TRUE(std::isnan(none.detection_rate()));
  EXPECT_TRUE(std::isnan(none.median_delay()));
  EXPECT_TRUE(std::isnan(none.median_abs_size_error()));
}

TEST(EvaluationCoverage, CountsIntervalsThatCoverTheTruth) {
  const auto results = records();
  const Coverage c = coverage_of(results, "all", 1e-12);
  EXPECT_EQ(c.raised, 2);
  EXPECT_EQ(c.covered, 1);
  EXPECT_NEAR(c.median_relative_half_width(), 0.5, 1e-12);
  EXPECT_EQ(coverage_of(results, "fault_tolerant", 1e-12).covered, 1);
  EXPECT_EQ(coverage_of(results, "basic", 1e-12).covered, 0);
  EXPECT_EQ(coverage_of(results, "all", 2e-12).raised, 0);  // run 3 has no size check
  EXPECT_TRUE(std::isnan(coverage_of(results, "all", 2e-12).median_relative_half_width()));
}

}  // namespace
}  // namespace leakmon::study
