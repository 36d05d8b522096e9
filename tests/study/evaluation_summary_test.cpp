// The evaluation's aggregation on hand-built run records (no simulation): false alarms only in
// monitored healthy time, detection only within the window, delays and sizes of the first raise
// after the onset, interval coverage, and the exact confidence bounds against scipy's values.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
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

// A program run for candidate 0 ("paper") with its alarms at the design threshold; monitoring
// from 100 s. Phases: hold 20 mm 0-200 s (80 kN/m: 2.5 MPa, judgeable), steps 200-500 s, hold
// 3 mm 500-700 s (0.38 MPa: not judgeable), sine 700-1000 s.
RunResult program_record(double leak, double onset, std::vector<Alarm> alarms) {
  RunResult r = record(0, sim::ControllerKind::basic, 1000.0, leak, onset, {});
  r.alarms.assign(1, std::vector<std::vector<Alarm>>(candidates()[0].raise_thresholds.size()));
  r.alarms[0][design_index(candidates()[0])] = std::move(alarms);
  using sim::PhaseKind;
  r.spec.phases = {{PhaseKind::hold, 0.0, 200.0, true, "hold 0.02"},
                   {PhaseKind::steps, 200.0, 500.0, true, "steps"},
                   {PhaseKind::hold, 500.0, 700.0, false, "hold 0.003"},
                   {PhaseKind::sine, 700.0, 1000.0, true, "sine 1 0.01"}};
  r.spec.leak_phase = leak > 0.0 ? r.spec.phase_at(onset) : -1;
  return r;
}

const PhaseKindScore& row(const std::vector<PhaseKindScore>& rows, const std::string& phase) {
  for (const auto& r : rows) {
    if (r.phase == phase) return r;
  }
  ADD_FAILURE() << "no row " << phase;
  return rows.front();
}

TEST(EvaluationPrograms, ScoresPerPhaseKindWithTheHoldsThatCannotBeJudged) {
  const std::vector<RunResult> results = {
      // Healthy: false alarms 5 s into the steps after the hold, in the quiet hold, and late in
      // the sine.
      program_record(0.0, 1e300, {{205.0, NAN}, {600.0, NAN}, {900.0, NAN}}),
      // A leak opening in the quiet hold at 550 s, raised 20 s into the sine: found (by the
      // sine's start + 60 s), delay counted from that start.
      program_record(1e-12, 550.0, {{720.0, NAN}}),
      // A leak opening in the sine at 750 s, raised 70 s later: found only later.
      program_record(1e-12, 750.0, {{820.0, NAN}}),
      // A leak opening in the steps at 300 s raised after 12 s; a false alarm in the first hold.
      program_record(2e-12, 300.0, {{150.0, NAN}, {312.0, NAN}}),
  };
  EXPECT_EQ(results[1].spec.detection_deadline(60.0), 760.0);
  EXPECT_EQ(results[2].spec.detection_deadline(60.0), 810.0);
  EXPECT_EQ(results[0].spec.phase_at(1000.0), 3);  // the run's last instant
  EXPECT_EQ(results[0].spec.phase_at(1000.5), -1);

  const auto rows = score_program_phases(results, 0, 60.0);
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_EQ(rows[1].phase, "hold");
  EXPECT_EQ(rows[2].phase, "hold (not judgeable)");
  // Healthy time from 100 s to each run's onset, split by phase.
  EXPECT_NEAR(row(rows, "hold").healthy_hours, 4 * 100.0 / 3600.0, 1e-12);
  EXPECT_NEAR(row(rows, "steps").healthy_hours, (300.0 + 300.0 + 300.0 + 100.0) / 3600.0, 1e-12);
  EXPECT_NEAR(row(rows, "hold (not judgeable)").healthy_hours, (200.0 + 50.0 + 200.0) / 3600.0,
              1e-12);
  EXPECT_NEAR(row(rows, "sine").healthy_hours, (300.0 + 50.0) / 3600.0, 1e-12);
  EXPECT_EQ(row(rows, "sweep").healthy_hours, 0.0);
  EXPECT_TRUE(std::isnan(row(rows, "sweep").false_alarms_per_hour()));
  // False alarms where they were raised; early ones within 30 s of the phase's start.
  EXPECT_EQ(row(rows, "steps").false_alarms, 1);
  EXPECT_EQ(row(rows, "steps").early_false_alarms, 1);
  EXPECT_EQ(row(rows, "steps").after_hold_false_alarms, 1);
  EXPECT_EQ(row(rows, "hold").false_alarms, 1);
  EXPECT_EQ(row(rows, "hold").early_false_alarms, 0);
  EXPECT_EQ(row(rows, "hold (not judgeable)").false_alarms, 1);
  EXPECT_EQ(row(rows, "sine").false_alarms, 1);
  EXPECT_EQ(row(rows, "sine").early_false_alarms, 0);
  const double steps_hours = row(rows, "steps").healthy_hours;
  EXPECT_NEAR(row(rows, "steps").false_alarms_per_hour_upper_95(),
              poisson_upper_95(1) / steps_hours, 1e-9);
  // Leaks per phase they opened in.
  EXPECT_EQ(row(rows, "hold (not judgeable)").leak_runs, 1);
  EXPECT_EQ(row(rows, "hold (not judgeable)").found, 1);
  ASSERT_EQ(row(rows, "hold (not judgeable)").delays.size(), 1u);
  EXPECT_NEAR(row(rows, "hold (not judgeable)").delays[0], 20.0, 1e-12);
  EXPECT_EQ(row(rows, "sine").leak_runs, 1);
  EXPECT_EQ(row(rows, "sine").found, 0);
  EXPECT_EQ(row(rows, "sine").found_late, 1);
  EXPECT_EQ(row(rows, "steps").leak_runs, 1);
  EXPECT_EQ(row(rows, "steps").found, 1);
  EXPECT_NEAR(row(rows, "steps").delays[0], 12.0, 1e-12);
  EXPECT_EQ(row(rows, "hold").leak_runs, 0);

  // By how the program starts: every one of these starts with a hold.
  const auto starts = score_program_starts(results, 0);
  ASSERT_EQ(starts.size(), 2u);
  EXPECT_TRUE(starts[0].starts_with_hold);
  EXPECT_EQ(starts[0].runs, 4);
  EXPECT_EQ(starts[0].false_alarms, 4);
  EXPECT_EQ(starts[0].runs_with_false_alarm, 2);
  EXPECT_NEAR(starts[0].healthy_hours, (900.0 + 450.0 + 650.0 + 200.0) / 3600.0, 1e-12);
  EXPECT_EQ(starts[1].runs, 0);
}

TEST(EvaluationWear, FindsTheSizeAtTheFirstRaiseAfterTheOnset) {
  auto wear_record = [](double final_size, double seconds, std::vector<Alarm> alarms) {
    RunResult r =
        record(0, sim::ControllerKind::basic, 100.0 + seconds + 90.0, final_size, 100.0, {});
    r.alarms.assign(1, std::vector<std::vector<Alarm>>(candidates()[0].raise_thresholds.size()));
    r.alarms[0][design_index(candidates()[0])] = std::move(alarms);
    r.spec.wear_seconds = seconds;
    return r;
  };
  const std::vector<RunResult> results = {
      // 3e-12 over 1 h (medium): raised at half way, 1.5e-12: just in time.
      wear_record(3e-12, 3600.0, {{1900.0, NAN}}),
      // 2e-12 over 4 h (slow): a false alarm before the wear, none after it.
      wear_record(2e-12, 14400.0, {{50.0, NAN}}),
      // 5e-12 over 10 min (fast): raised at 40 %, 2e-12: too late.
      wear_record(5e-12, 600.0, {{340.0, NAN}}),
      // A leak that opens at once is no wear run.
      record(1, sim::ControllerKind::basic, 400.0, 1e-12, 280.0, {{290.0, NAN}}),
  };
  EXPECT_TRUE(results[0].spec.wear_run());
  EXPECT_FALSE(results[3].spec.wear_run());
  EXPECT_DOUBLE_EQ(results[0].spec.leak_at(1900.0), 1.5e-12);
  const auto rows = score_wear(results, 0);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].growth, "all");
  EXPECT_EQ(rows[0].runs, 3);
  EXPECT_EQ(rows[0].found, 2);
  EXPECT_EQ(rows[0].found_before_target, 1);
  ASSERT_EQ(rows[0].found_at.size(), 2u);
  EXPECT_DOUBLE_EQ(rows[0].found_at[1], 2e-12);
  EXPECT_EQ(rows[1].growth, "slow");
  EXPECT_EQ(rows[1].runs, 1);
  EXPECT_EQ(rows[1].found, 0);
  EXPECT_EQ(rows[2].runs, 1);
  EXPECT_EQ(rows[2].found_before_target, 1);
  EXPECT_EQ(rows[3].runs, 1);
  EXPECT_EQ(rows[3].found_before_target, 0);
  // The generic tables count the wear runs' healthy time, not their leaks.
  const Rates rates = rates_of(results, 0, 0, "all", 0.0, 60.0);
  EXPECT_EQ(rates.leak_runs, 1);
  EXPECT_NEAR(rates.healthy_hours, 180.0 / 3600.0, 1e-12);  // run 3 only: onsets at 100 s
  EXPECT_EQ(coverage_of(results, "all", 3e-12).raised, 0);
}

}  // namespace
}  // namespace leakmon::study
