// The evaluation harness called directly on a handful of short simulated runs: case generation
// reproduces a master seed and shapes each condition's scenario, the runner replays through the
// daemon's pipeline, a healthy rig raises nothing and a large leak is found within a minute.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <variant>

#include "capture/capture.hpp"
#include "study/case_generation.hpp"
#include "study/evaluation_runner.hpp"
#include "study/evaluation_summary.hpp"
#include "study/evaluation_writers.hpp"
#include "tests/model/test_seed.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::study {
namespace {

EvaluationOptions short_options(std::uint64_t seed) {
  EvaluationOptions options;
  options.healthy_runs = 1;
  options.healthy_seconds = 150.0;
  options.runs_per_leak = 1;
  options.leak_sizes = {5e-12};
  options.learn_seconds = 30.0;
  options.after_onset_seconds = 60.0;
  options.seed = seed;
  options.jobs = 2;
  std::printf("evaluation seed %llu\n", static_cast<unsigned long long>(seed));
  return options;
}

std::size_t candidate_index(const char* label) {
  const auto all = candidates();
  for (std::size_t c = 0; c < all.size(); ++c) {
    if (all[c].label == label) return c;
  }
  ADD_FAILURE() << "no candidate " << label;
  return 0;
}

TEST(CaseGeneration, PlansHealthyThenLeakRunsAndReproducesTheSeed) {
  EvaluationOptions options = short_options(7);
  options.healthy_runs = 2;
  options.runs_per_leak = 2;
  options.leak_sizes = {1e-12, 2e-12};
  options.effects = {"coulomb_friction"};
  const auto plan = plan_conditions(options);
  ASSERT_EQ(plan.size(), 6u);
  EXPECT_TRUE(std::holds_alternative<HealthyCondition>(plan[1].kind));
  ASSERT_TRUE(std::holds_alternative<LeakCondition>(plan[4].kind));
  EXPECT_EQ(std::get<LeakCondition>(plan[4].kind).coefficient, 2e-12);
  EXPECT_EQ(plan[5].effects, options.effects);

  const auto runs = draw_runs(options);
  const auto again = draw_runs(options);
  ASSERT_EQ(runs.size(), 6u);
  const double monitor_from = options.settle_seconds + options.learn_seconds + 1.0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const RunSpec& r = runs[i];
    EXPECT_EQ(r.id, static_cast<int>(i));
    EXPECT_EQ(r.scenario.params.K_s, again[i].scenario.params.K_s);  // same seed, same rig
    EXPECT_GE(r.scenario.params.K_s, 40e3);
    EXPECT_LE(r.scenario.params.K_s, 120e3);
    EXPECT_EQ(r.scenario.seed, simulation_seed(7, r.id));
    EXPECT_EQ(r.monitor_from, monitor_from);
    EXPECT_TRUE(r.scenario.effects.coulomb_friction.has_value());
    if (i < 2) {
      EXPECT_EQ(r.leak, 0.0);
      EXPECT_EQ(r.scenario.duration_s, options.healthy_seconds);
      EXPECT_FALSE(r.scenario.effects.internal_leakage.has_value());
    } else {
      EXPECT_EQ(r.leak, i < 4 ? 1e-12 : 2e-12);
      EXPECT_GE(r.onset, monitor_from + 20.0);
      EXPECT_LE(r.onset, monitor_from + 60.0);
      EXPECT_DOUBLE_EQ(r.scenario.duration_s, r.onset + options.after_onset_seconds);
      ASSERT_TRUE(r.scenario.effects.internal_leakage.has_value());
    }
  }
  EXPECT_NE(runs[0].scenario.params.K_s, runs[1].scenario.params.K_s);
  EXPECT_NE(draw_runs(short_options(8))[0].scenario.params.K_s, runs[0].scenario.params.K_s);

  // A condition on its own: a leak case from a given seed and draw stream.
  std::mt19937_64 draws(11);
  const RunSpec one = generate_case(3, 1234, {LeakCondition{3e-12, 75.0}, {}}, draws, options);
  EXPECT_EQ(one.leak, 3e-12);
  EXPECT_EQ(one.scenario.seed, 1234u);
  EXPECT_DOUBLE_EQ(one.scenario.duration_s, one.onset + 75.0);
  EXPECT_EQ(one.scenario.controller, sim::ControllerKind::fault_tolerant);  // odd id
}

// The lengths and values of MODEL.md's "Test programs" table, for checking the draws.
struct PhaseRange {
  double minutes_lo, minutes_hi;
};
PhaseRange typical_minutes(sim::PhaseKind kind) {
  switch (kind) {
    case sim::PhaseKind::hold:
      return {1.0, 10.0};
    case sim::PhaseKind::sweep:
      return {1.0, 5.0};
    default:
      return {2.0, 10.0};
  }
}

void expect_typical_values(const sim::Phase& phase) {
  switch (phase.kind) {
    case sim::PhaseKind::steps:
      break;
    case sim::PhaseKind::hold:
      EXPECT_LE(std::abs(phase.X), 0.05);
      break;
    case sim::PhaseKind::sine:
      EXPECT_GE(phase.F, 0.2);
      EXPECT_LE(phase.F, 3.0);
      EXPECT_GE(phase.A, 0.005);
      EXPECT_LE(phase.A, 0.04);
      break;
    case sim::PhaseKind::sweep:
      EXPECT_GE(phase.F0, 0.1);
      EXPECT_LE(phase.F0, 0.5);
      EXPECT_GE(phase.F1, 1.5);
      EXPECT_LE(phase.F1, 4.0);
      EXPECT_GE(phase.A, 0.005);
      EXPECT_LE(phase.A, 0.03);
      break;
    case sim::PhaseKind::triangle:
      EXPECT_GE(phase.P, 1.0);
      EXPECT_LE(phase.P, 8.0);
      EXPECT_GE(phase.A, 0.01);
      EXPECT_LE(phase.A, 0.045);
      break;
  }
}

// programs and wear: every phase kind gets its leaks, the draws follow MODEL.md's table, the
// truth marks holds too close to the spring's rest as not judgeable, and a master seed
// reproduces every run. A fresh seed each run (printed).
TEST(CaseGeneration, ProgramsAndWearFollowTheModelAndReproduceTheSeed) {
  EvaluationOptions options = short_options(test::model_test_seed("programs and wear"));
  options.conditions = {"programs", "wear"};
  options.healthy_runs = 20;
  options.runs_per_leak = 10;  // per size 5 under programs, 5 wear runs
  options.leak_sizes = {1e-12, 2e-12};
  options.time_scale = 0.5;
  const auto runs = draw_runs(options);
  ASSERT_EQ(runs.size(), 40u);
  std::map<sim::PhaseKind, int> leaks_in;
  int starts_with_hold = 0, programs = 0, not_judgeable = 0, wear_runs = 0;
  for (const RunSpec& run : runs) {
    SCOPED_TRACE("run " + std::to_string(run.id));
    const bool program = run.condition.operating == "programs";
    if (!program) {
      // wear: the steps rig with the cooler's cycle and `temp`; wear in leak runs only.
      EXPECT_TRUE(run.phases.empty());
      EXPECT_TRUE(run.scenario.program.empty());
      EXPECT_TRUE(run.scenario.record.temp);
      ASSERT_TRUE(run.scenario.conditions.temperature.has_value());
      EXPECT_EQ(run.scenario.conditions.temperature->kind, sim::TemperatureProfile::Kind::cooler);
      if (run.leak == 0.0) {
        EXPECT_FALSE(run.wear_run());
        continue;
      }
      ++wear_runs;
      ASSERT_TRUE(run.wear_run());
      EXPECT_GE(run.leak, 1e-12);
      EXPECT_LE(run.leak, 5e-12);
      EXPECT_GE(run.wear_seconds, 600.0 * options.time_scale);
      EXPECT_LE(run.wear_seconds, 14400.0 * options.time_scale);
      ASSERT_TRUE(run.scenario.effects.internal_leakage.has_value());
      const sim::InternalLeakage& leak = *run.scenario.effects.internal_leakage;
      EXPECT_EQ(leak.C_L, run.leak);
      EXPECT_EQ(leak.onset_s, run.onset);
      EXPECT_EQ(leak.ramp_s, run.wear_seconds);
      EXPECT_DOUBLE_EQ(run.scenario.duration_s,
                       run.onset + run.wear_seconds + options.after_onset_seconds);
      EXPECT_DOUBLE_EQ(run.leak_at(run.onset + 0.5 * run.wear_seconds), 0.5 * run.leak);
      EXPECT_EQ(run.leak_at(run.onset - 1.0), 0.0);
      EXPECT_EQ(run.leak_at(run.scenario.duration_s), run.leak);
      continue;
    }
    ++programs;
    const auto& p = run.scenario.program;
    ASSERT_GE(p.size(), 3u);
    ASSERT_LE(p.size(), 8u);
    ASSERT_EQ(run.phases.size(), p.size());
    EXPECT_FALSE(run.scenario.record.temp);  // the stationary rig
    starts_with_hold += p.front().kind == sim::PhaseKind::hold ? 1 : 0;
    double start = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      SCOPED_TRACE(p[i].notation());
      expect_typical_values(p[i]);
      const PhaseRange range = typical_minutes(p[i].kind);
      EXPECT_GE(p[i].duration_s, 60.0 * range.minutes_lo * options.time_scale - 1e-9);
      // Only the phase a leak opens in may be lengthened (to open 20 s after learning).
      if (static_cast<int>(i) != run.leak_phase) {
        EXPECT_LE(p[i].duration_s, 60.0 * range.minutes_hi * options.time_scale + 1e-9);
      }
      const ProgramPhase& truth = run.phases[i];
      EXPECT_EQ(truth.kind, p[i].kind);
      EXPECT_EQ(truth.notation, p[i].notation());
      EXPECT_DOUBLE_EQ(truth.start, std::min(start, run.scenario.duration_s));
      start += p[i].duration_s;
      const double load = std::abs(run.scenario.params.K_s * p[i].X) / run.scenario.params.A();
      EXPECT_EQ(truth.judgeable, p[i].kind != sim::PhaseKind::hold || load >= 1e6);
      not_judgeable += truth.judgeable ? 0 : 1;
    }
    EXPECT_EQ(run.phases.back().end, run.scenario.duration_s);
    if (run.leak == 0.0) {
      // A healthy run lasts as long as its program.
      EXPECT_EQ(run.leak_phase, -1);
      EXPECT_DOUBLE_EQ(run.scenario.duration_s, start);
      EXPECT_FALSE(run.scenario.effects.internal_leakage.has_value());
      continue;
    }
    // The leak opens inside the planned kind's phase, neither the first nor the last, 20 s or
    // more after learning; a run goes on for the window after the onset, and past the next
    // phase's start plus the window when the phase cannot be judged.
    const auto planned = std::get<LeakCondition>(run.condition.kind).phase;
    ASSERT_TRUE(planned.has_value());
    ASSERT_GE(run.leak_phase, 1);
    ASSERT_LE(run.leak_phase, static_cast<int>(p.size()) - 2);
    const ProgramPhase& opened_in = run.phases[static_cast<std::size_t>(run.leak_phase)];
    EXPECT_EQ(opened_in.kind, *planned);
    EXPECT_EQ(run.phase_at(run.onset), run.leak_phase);
    EXPECT_GE(run.onset, run.monitor_from + 20.0);
    EXPECT_GE(run.onset, opened_in.start);
    EXPECT_LT(run.onset, opened_in.end);
    ASSERT_TRUE(run.scenario.effects.internal_leakage.has_value());
    EXPECT_EQ(run.scenario.effects.internal_leakage->onset_s, run.onset);
    EXPECT_EQ(run.scenario.effects.internal_leakage->ramp_s, 0.0);
    EXPECT_GE(run.scenario.duration_s, run.onset + options.after_onset_seconds - 1e-9);
    if (opened_in.judgeable) {
      EXPECT_EQ(run.detection_deadline(60.0), run.onset + 60.0);
    } else {
      EXPECT_EQ(run.detection_deadline(60.0), opened_in.end + 60.0);
      EXPECT_GE(run.scenario.duration_s, opened_in.end + 60.0);
    }
    ++leaks_in[opened_in.kind];
  }
  EXPECT_EQ(programs, 20);
  EXPECT_EQ(wear_runs, 10);
  // Every kind twice (the kinds in turn over the program leak runs of both sizes).
  for (const sim::PhaseKind kind : sim::kPhaseKinds) {
    EXPECT_EQ(leaks_in[kind], 2) << sim::to_string(kind);
  }
  // Half of the programs start with a hold (20 programs: all or none has probability 2e-6).
  EXPECT_GT(starts_with_hold, 0);
  EXPECT_LT(starts_with_hold, programs);
  std::printf("%d of %d programs start with a hold; %d holds not judgeable\n", starts_with_hold,
              programs, not_judgeable);

  // The master seed reproduces every run; another seed draws other programs.
  const auto again = draw_runs(options);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    ASSERT_EQ(again[i].scenario.program.size(), runs[i].scenario.program.size());
    for (std::size_t k = 0; k < runs[i].scenario.program.size(); ++k) {
      EXPECT_EQ(again[i].scenario.program[k].notation(), runs[i].scenario.program[k].notation());
      EXPECT_EQ(again[i].scenario.program[k].duration_s, runs[i].scenario.program[k].duration_s);
    }
    EXPECT_EQ(again[i].onset, runs[i].onset);
    EXPECT_EQ(again[i].scenario.duration_s, runs[i].scenario.duration_s);
    EXPECT_EQ(again[i].leak, runs[i].leak);
  }
  EvaluationOptions other = options;
  other.seed = options.seed + 1;
  EXPECT_NE(draw_runs(other)[0].scenario.duration_s, runs[0].scenario.duration_s);
}

// One healthy and one large-leak run through the runner, the aggregation and the writers.
TEST(EvaluationRun, HealthyRigIsQuietAndALargeLeakIsFoundWithinAMinute) {
  for (std::uint64_t seed : {3u, 4u}) {
    EvaluationOptions options = short_options(seed);
    options.out = test::scratch_dir("study_evaluation_run_" + std::to_string(seed));
    options.keep_captures = {1};
    const auto runs = draw_runs(options);
    std::size_t progress_calls = 0;
    const auto results = run_evaluation(runs, options, [&](std::size_t done, std::size_t total) {
      EXPECT_EQ(done, ++progress_calls);
      EXPECT_EQ(total, runs.size());
    });
    ASSERT_EQ(results.size(), 2u);
    EXPECT_EQ(progress_calls, 2u);
    EXPECT_EQ(results[1].spec.id, 1);
    EXPECT_TRUE(std::filesystem::exists(options.out / "run-1.csv"));
    EXPECT_FALSE(std::filesystem::exists(options.out / "run-0.csv"));

    const auto all = candidates();
    for (const char* label : {"default", "flow_balance"}) {
      const std::size_t c = candidate_index(label);
      const std::size_t design = design_index(all[c]);
      // The healthy run raises nothing at the design threshold.
      EXPECT_TRUE(results[0].alarms[c][design].empty()) << label << " seed " << seed;
      const Rates rates = rates_of(results, c, design, "all", 0.0, options.detect_within);
      EXPECT_EQ(rates.false_alarms, 0) << label << " seed " << seed;
      EXPECT_EQ(rates.leak_runs, 1);
      EXPECT_EQ(rates.detected, 1) << label << " seed " << seed;
      ASSERT_EQ(rates.delays.size(), 1u);
      EXPECT_LT(rates.delays[0], 60.0) << label << " seed " << seed;
      EXPECT_GE(rates.delays[0], 0.0);
    }
    // The flow balance's first raise carries a size whose interval is finite.
    EXPECT_FALSE(std::isnan(results[1].size_check.leak_coefficient));
    EXPECT_GT(results[1].size_check.half_width, 0.0);

    write_runs_json(options.out / "runs.json", results);
    write_summaries(options.out, options, results);
    for (const char* file :
         {"runs.json", "summary.json", "summary.tsv", "summary.md", "size_coverage.tsv"}) {
      EXPECT_GT(std::filesystem::file_size(options.out / file), 100u) << file;
    }
  }
}

// Restart runs: the daemon stops after learning, its state saved; the restarted replay resumes it
// on a capture of the rig 1-5 K warmer or cooler, where a leak run's leak has opened meanwhile.
TEST(EvaluationRun, RestartResumesTheStateAndFindsALeakThatOpenedWhileDown) {
  EvaluationOptions options = short_options(8);
  options.healthy_runs = 2;
  options.runs_per_leak = 2;
  options.leak_sizes = {2e-12};
  options.conditions = {"restart"};
  options.after_restart_seconds = 120.0;
  const auto runs = draw_runs(options);
  ASSERT_EQ(runs.size(), 4u);
  for (const auto& run : runs) {
    ASSERT_TRUE(run.after_restart.has_value());
    const double change = std::abs(run.temp_after - run.temp_before);
    EXPECT_GE(change, 1.0);
    EXPECT_LE(change, 5.0);
    EXPECT_GT(run.stop_at, run.monitor_from);
    EXPECT_EQ(run.restart_at, run.stop_at + run.downtime);
    // The first capture ends at the stop and has no leak; a leak run's leak is there from the
    // restart on, and it is scored from the restart.
    EXPECT_EQ(run.scenario.duration_s, run.stop_at);
    EXPECT_FALSE(run.scenario.effects.internal_leakage.has_value());
    if (run.leak > 0.0) {
      EXPECT_EQ(run.onset, run.restart_at);
      ASSERT_TRUE(run.after_restart->effects.internal_leakage.has_value());
      EXPECT_EQ(run.after_restart->effects.internal_leakage->onset_s, 0.0);
    }
  }
  const auto results = run_evaluation(runs, options);
  for (const auto& r : results) EXPECT_GT(r.states_restored, 0) << "run " << r.spec.id;
  for (const char* label : {"default", "default_temp"}) {
    const RestartScore score = score_restarts(results, candidate_index(label), 60.0);
    EXPECT_EQ(score.restored, 4) << label;
    EXPECT_EQ(score.leak_runs, 2);
    EXPECT_EQ(score.found, 2) << label;
    EXPECT_EQ(score.healthy_runs, 2);
    EXPECT_EQ(score.healthy_raised, 0) << label;
    EXPECT_EQ(score.raised_before_stop, 0) << label;
    // The restarted detector did not relearn: it raises within seconds, not after a learning
    // period (30 s here).
    for (double delay : score.delays) EXPECT_LT(delay, 30.0) << label;
  }
  // The downtime is no monitored time.
  const Rates rates =
      rates_of(results, candidate_index("default"),
               design_index(candidates()[candidate_index("default")]), "all", 0.0, 60.0);
  double monitored = 0.0;
  for (const auto& r : results) {
    monitored += (r.spec.stop_at - r.spec.monitor_from) +
                 (r.spec.leak > 0.0 ? 0.0 : r.seconds - r.spec.restart_at);
  }
  EXPECT_NEAR(rates.healthy_hours, monitored / 3600.0, 1e-9);
}

// Sensor-fault runs: every kind in turn, a leak opening during every second fault; each fault is
// named on its channel within 5 s of showing, none raises internal_leakage, and the leak is found
// within a minute of the fault's end.
TEST(EvaluationRun, SensorFaultRunsAreNamedPerKindAndTheLeakIsFoundAfterwards) {
  EvaluationOptions options = short_options(9);
  options.healthy_runs = 0;
  options.runs_per_leak = 0;
  options.sensor_fault_runs = 12;
  options.after_fault_seconds = 65.0;  // the minute after the fault, and a little
  options.out = test::scratch_dir("study_evaluation_sensor_faults");
  const auto runs = draw_runs(options);
  ASSERT_EQ(runs.size(), 12u);
  for (const auto& run : runs) {
    EXPECT_TRUE(run.sensor_fault_run);
    EXPECT_FALSE(run.fault_channel.empty());
    EXPECT_GT(run.fault_start, run.monitor_from);
    if (run.leak > 0.0) {
      EXPECT_GE(run.onset, run.fault_start);
      EXPECT_LT(run.onset, run.fault_end);
    }
  }
  const auto results = run_evaluation(runs, options);
  const auto scores = score_sensor_faults(results, options.detect_within);
  ASSERT_EQ(scores.size(), 6u);  // frozen, saturated high/low, spikes, dropout zero/gap
  int leak_runs = 0;
  for (const auto& score : scores) {
    SCOPED_TRACE(score.variant);
    EXPECT_EQ(score.runs + score.never_seen, 2);
    EXPECT_EQ(score.leak_runs, 1);  // each kind once with a leak opening during the fault
    EXPECT_EQ(score.named, score.runs);
    EXPECT_EQ(score.wrong_channel, 0);
    EXPECT_EQ(score.leakage_raised, 0);
    EXPECT_EQ(score.leak_found, score.leak_runs);
    leak_runs += score.leak_runs;
  }
  EXPECT_EQ(leak_runs, 6);
  for (const auto& r : results) {
    // A spikes fault shows at its first spike, not at its start.
    if (r.spec.fault_kind == "spikes" && !std::isnan(r.spec.fault_seen)) {
      EXPECT_GE(r.spec.fault_seen, r.spec.fault_start);
      EXPECT_LT(r.spec.fault_seen, r.spec.fault_end);
    } else if (r.spec.fault_kind != "spikes") {
      EXPECT_EQ(r.spec.fault_seen, r.spec.fault_start);
    }
  }
  // The generic tables leave these runs out (their leak opens inside a fault on purpose).
  const Rates rates =
      rates_of(results, candidate_index("default"),
               design_index(candidates()[candidate_index("default")]), "all", 0.0, 60.0);
  EXPECT_EQ(rates.leak_runs, 0);
  EXPECT_EQ(rates.healthy_hours, 0.0);
  write_runs_json(options.out / "runs.json", results);
  write_condition_summaries(options.out, options, results);
  std::ifstream json(options.out / "runs.json");
  std::string text, line;
  while (std::getline(json, line)) text += line;
  EXPECT_NE(text.find("\"fault\": {\"channel\""), std::string::npos);
  EXPECT_NE(text.find("\"sensor_fault_alarms\": [{\"t\""), std::string::npos);
}

TEST(EvaluationRun, AFailingRunIsReportedWithItsId) {
  EvaluationOptions options = short_options(5);
  options.out = test::scratch_dir("study_evaluation_failure") + "/missing/dir";
  options.keep_captures = {0};  // the capture cannot be written there
  auto runs = draw_runs(options);
  runs.resize(1);
  runs[0].scenario.duration_s = 5.0;
  try {
    run_evaluation(runs, options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("run 0: ", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace leakmon::study
