// Which cases the evaluation simulates. A Condition says what is wrong (or not) with a run; the
// case generator turns it, with the run's seed and the study's rig draws, into the scenario to
// simulate plus the truth the aggregation scores against (RunSpec). The runner sees only
// RunSpecs, so a new kind of condition (a drifting oil temperature, a sensor fault, a supply
// change) is a new alternative in Condition::Kind and a branch in generate_case, nothing else.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include "sim/scenario.hpp"
#include "study/evaluation_options.hpp"

namespace leakmon::study {

// A healthy rig for `seconds`: only false alarms can happen.
struct HealthyCondition {
  double seconds = 0.0;
};

// A healthy stretch after learning, then an internal leak of C_L `coefficient` [m^3/(s Pa)]
// switched on for `after_onset_seconds`.
struct LeakCondition {
  double coefficient = 0.0;
  double after_onset_seconds = 0.0;
};

struct Condition {
  using Kind = std::variant<HealthyCondition, LeakCondition>;
  Kind kind;
  std::vector<std::string> effects;      // MODEL.md effects on from the start (default parameters)
  std::string operating = "stationary";  // one of kConditionNames: how the rig drifts
};

// One run to simulate and the truth to score it against.
struct RunSpec {
  int id = 0;
  Condition condition;
  sim::Scenario scenario;
  double leak = 0.0;        // C_L [m^3/(s Pa)], 0 healthy
  double onset = 1e300;     // leak onset [s]
  double monitor_from = 0;  // end of settle + learning [s]
  // sensor-faults: the injected fault (channel name and kind as the alarm names them), and when.
  std::string fault_channel, fault_kind;
  double fault_start = NAN, fault_end = NAN;
};

// The evaluation's conditions in run order: healthy_runs healthy runs, then runs_per_leak leak
// runs per leak size, each with the options' effects.
std::vector<Condition> plan_conditions(const EvaluationOptions& options);

// Seed of run `id`'s simulation (noise, reference) in a study with master seed `seed`.
std::uint64_t simulation_seed(std::uint64_t seed, int id);

// The scenario of run `id` under `condition`. The rig (controller, spring, beta, Kv, m, b,
// reference amplitude) and the onset are drawn from `rig_draws`, the study's one stream shared
// by all runs in order, so a master seed reproduces every run; `seed` seeds the simulation.
RunSpec generate_case(int id, std::uint64_t seed, const Condition& condition,
                      std::mt19937_64& rig_draws, const EvaluationOptions& options);

// plan_conditions -> generate_case for every run, from the master seed.
std::vector<RunSpec> draw_runs(const EvaluationOptions& options);

}  // namespace leakmon::study
