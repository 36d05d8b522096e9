// Other rigs running test programs (`leakmon evaluate --rigs other --conditions programs`,
// docs/detection.md "Other rigs running test programs"): the case generator scales a program to
// the rig and the rig runs it, and two runs of the evaluation that raised on healthy rigs, drawn
// again as it drew them and replayed through the daemon's pipeline. Label `long` (simulations of
// 20 minutes of programs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "capture/capture.hpp"
#include "config/yaml_reader.hpp"
#include "pipeline/replay.hpp"
#include "sim/rig_draw.hpp"
#include "sim/simulate.hpp"
#include "study/case_generation.hpp"
#include "study/evaluation_options.hpp"
#include "study/rig_cases.hpp"
#include "tests/model/test_seed.hpp"

namespace leakmon::study {
namespace {

// Other rigs under the drifting conditions and programs (`--rigs other --conditions ...`): a
// program's positions and amplitudes scale as the rig's steps do and the rig runs it, leaks and
// seals that wear are that share of the rig's valve, a supply change that share of its supply.
// A fresh seed each run (printed).
TEST(CaseGeneration, OnOtherRigsProgramsScaleAsTheRigsStepsAndTheRigRunsThem) {
  EvaluationOptions options;
  options.seed = test::model_test_seed("other rigs, programs");
  options.learn_seconds = 30.0;
  options.after_onset_seconds = 60.0;
  options.rigs = "other";
  options.conditions = {"programs", "wear", "supply"};
  options.healthy_runs = 9;
  options.runs_per_leak = 9;
  options.leak_sizes = {1e-12};
  options.time_scale = 0.3;
  const auto runs = draw_runs(options);
  ASSERT_EQ(runs.size(), 18u);
  int programs = 0, wear_runs = 0, supply_runs = 0;
  for (const RunSpec& run : runs) {
    SCOPED_TRACE("run " + std::to_string(run.id));
    const sim::Parameters& p = run.scenario.params;
    EXPECT_DOUBLE_EQ(run.valve_scale, p.Kv / kPaperValveCoefficient);
    if (run.condition.operating == "programs") {
      ++programs;
      // The steps' scale: the rig's largest step against the paper's 50 mm (halved where the
      // rig could not run the program at it).
      const double scale = run.scenario.reference.amp_max / 0.05;
      ASSERT_FALSE(run.scenario.program.empty());
      for (const sim::Phase& phase : run.scenario.program) {
        SCOPED_TRACE(phase.notation());
        EXPECT_LE(std::abs(phase.X), 0.05 * scale + 1e-12);
        EXPECT_LE(phase.A, 0.045 * scale + 1e-12);
      }
      sim::Scenario trial = run.scenario;
      trial.effects = sim::Effects{};
      for (auto& phase : trial.program) phase.duration_s = std::min(phase.duration_s, 20.0);
      trial.duration_s = sim::program_seconds(trial.program);
      const sim::Viability viable = sim::check_viability(trial, trial.duration_s);
      EXPECT_TRUE(viable.ok) << viable.reason;
      if (run.leak > 0.0) {
        ASSERT_TRUE(run.scenario.effects.internal_leakage.has_value());
        EXPECT_DOUBLE_EQ(run.leak, 1e-12 * run.valve_scale);
        EXPECT_EQ(run.scenario.effects.internal_leakage->C_L, run.leak);
      }
    } else if (run.condition.operating == "wear" && run.leak > 0.0) {
      ++wear_runs;
      ASSERT_TRUE(run.wear_run());
      EXPECT_GE(run.leak, 1e-12 * run.valve_scale);
      EXPECT_LE(run.leak, 5e-12 * run.valve_scale);
    } else if (run.condition.operating == "supply") {
      ++supply_runs;
      const double share = p.ps / sim::Parameters{}.ps;
      ASSERT_FALSE(run.scenario.conditions.supply.empty());
      for (const auto& change : run.scenario.conditions.supply) {
        EXPECT_GE(change.ps, share * 13e6 - 1.0);
        EXPECT_LE(change.ps, share * 20e6 + 1.0);
      }
    }
  }
  EXPECT_EQ(programs, 6);
  EXPECT_EQ(wear_runs, 3);
  EXPECT_EQ(supply_runs, 6);
  // On the paper's rig the valve is the paper's.
  options.rigs = "paper";
  for (const RunSpec& run : draw_runs(options)) EXPECT_EQ(run.valve_scale, 1.0);
}

// `leakmon evaluate --rigs other --conditions programs --healthy-runs 40 --runs-per-leak 30
// --leaks 1e-12 --seed 2611` (docs/detection.md "Other rigs running test programs"): its runs
// as the evaluation drew them. Healthy runs come first, so the first ones are drawn alike here.
std::vector<RunSpec> programs_on_other_rigs(int healthy_runs) {
  EvaluationOptions options;
  options.rigs = "other";
  options.conditions = {"programs"};
  options.healthy_runs = healthy_runs;
  options.runs_per_leak = 0;
  options.leak_sizes = {1e-12};
  options.seed = 2611;
  return draw_runs(options);
}

// The raises of the default replay of the capture, its detector given these options (YAML).
int raised_with(const capture::Capture& capture, const std::string& detector_options) {
  pipeline::DaemonConfig config = pipeline::default_replay_config(capture);
  if (!detector_options.empty()) {
    config.actuators.at(0).detector_options =
        config::ConfigNode::load_string(detector_options, "test");
  }
  const pipeline::ReplayResult replay = pipeline::replay_capture(capture, config);
  return static_cast<int>(
      std::count_if(replay.events.begin(), replay.events.end(),
                    [](const auto& e) { return e.kind == io::EventKind::alarm_raised; }));
}

// Run 13 of that evaluation: a rig not described (13.3 MPa against the table's 17.2, a 2.3e-6
// valve on a 68 mm bore) that sweeps for 400 s before it first rests. The default with u and x
// (`flow_law`) integrated the valve's flow with the stated supply until the steps' first rest
// and raised 5 times on the healthy rig; reading the supply in motion too, it learns at the
// rig's own supply and raises nothing.
TEST(EvaluationRun, ARigNotDescribedThatNeverRestsIsJudgedAtItsOwnSupply) {
  const std::vector<RunSpec> runs = programs_on_other_rigs(14);
  const RunSpec& run = runs.at(13);
  ASSERT_NEAR(run.scenario.params.ps, 13.2911e6, 1e3);  // the evaluation's draw
  const capture::Capture capture = sim::simulate(run.scenario);
  const int before = raised_with(capture, "supply_motion_seconds: 0\n");
  const int after = raised_with(capture, "");
  std::printf("raised with the supply read at rest only: %d; read in motion too: %d\n", before,
              after);
  EXPECT_GT(before, 0);
  EXPECT_EQ(after, 0);
}

// Run 2 of that evaluation: a rig not described (a 70 mm bore at 12.7 MPa) whose tank sits at
// 0.76 MPa, the table's being 0.1. The chambers give ps + pt, so both lands' drops came out too
// large by the difference, which bends the orifice law with the load's sign as a leak does: 22
// raises in its program of steps, a sweep, holds and sines. The tank offset's regressor takes it
// up (learned on the steps: the tank at 0.71 MPa); one raise is left, at the start of the hold
// after the sweep (docs/detection.md).
TEST(EvaluationRun, ARigNotDescribedWithItsTankAboveTheStatedLearnsItsTankPressure) {
  const std::vector<RunSpec> runs = programs_on_other_rigs(3);
  const RunSpec& run = runs.at(2);
  ASSERT_NEAR(run.scenario.params.pt, 0.757244e6, 1e3);  // the evaluation's draw
  const capture::Capture capture = sim::simulate(run.scenario);
  const int before = raised_with(capture, "learn_tank_pressure: false\n");
  const int after = raised_with(capture, "");
  std::printf("raised with the stated tank pressure: %d; with its error learned: %d\n", before,
              after);
  EXPECT_GE(before, 10);
  EXPECT_LE(after, 1);
}

// Run 4 of that evaluation: a 296 kg rig whose hydraulic mode (12.9 Hz) lies below the band the
// index reads. Told its rig, the pressure-only actuators announce detection_blind; they went on
// deciding and raised internal_leakage on the healthy rig in its program (110-160 s). Blind,
// they now judge nothing and raise nothing, and say why.
TEST(EvaluationRun, ABlindPressureOnlyActuatorRaisesNothing) {
  const std::vector<RunSpec> runs = programs_on_other_rigs(5);
  const RunSpec& run = runs.at(4);
  ASSERT_NEAR(run.scenario.params.m, 296.4, 0.1);  // the evaluation's draw
  EvaluationOptions options;
  options.rigs = "other";
  const RigRunResult result = evaluate_rig_run(run, options);
  const auto all = rig_candidates();
  for (std::size_t c = 0; c < all.size(); ++c) {
    if (all[c].u || !all[c].told) continue;  // the told pressure-only actuators
    SCOPED_TRACE(all[c].label);
    EXPECT_TRUE(result.blind[c]);
    EXPECT_TRUE(result.run.alarms[c][0].empty());
  }
}

}  // namespace
}  // namespace leakmon::study
