// Which cases the evaluation simulates. A Condition says what is wrong (or not) with a run; the
// case generator turns it, with the run's seed and the study's rig draws, into the scenario to
// simulate plus the truth the aggregation scores against (RunSpec). The runner sees only
// RunSpecs, so a new kind of condition (a drifting oil temperature, a sensor fault, a supply
// change) is a new alternative in Condition::Kind and a branch in generate_case, nothing else.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
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

// A sensor fault of one transducer (its kind drawn) after learning; with `coefficient` > 0 an
// internal leak of that C_L opens during the fault. The run goes on for `after_fault_seconds`
// after the fault has cleared, so that one sees the leak decision work again.
struct SensorFaultCondition {
  double coefficient = 0.0;
  double after_fault_seconds = 0.0;
  // 0 frozen, 1 saturated high, 2 saturated low, 3 spikes, 4 dropout to zero, 5 dropout to gaps
  int kind = 0;
};

struct Condition {
  using Kind = std::variant<HealthyCondition, LeakCondition, SensorFaultCondition>;
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
  std::string fault_variant;  // kind with its variant: saturated_high/_low, dropout_zero/_gap
  double fault_start = NAN, fault_end = NAN;
  // When the fault first shows in the capture: its start, or the first spike (set by the runner,
  // which knows the injected spikes).
  double fault_seen = NAN;
  // A SensorFaultCondition run: scored per fault kind (write_condition_summaries), not in the
  // generic tables (its leak opens inside a fault on purpose).
  bool sensor_fault_run = false;
  // restart: the daemon is stopped at `stop_at` (the end of `scenario`, after which its state is
  // saved) and started again `downtime` seconds later on `after_restart`, a capture of the same
  // rig from then on (its leak, if any, opened during the downtime), resuming what it learned.
  // Times after the restart are stated on the first capture's clock: restart_at = stop_at +
  // downtime. `onset` is restart_at for a leak run, so "detected within 60 s" means of the restart.
  std::optional<sim::Scenario> after_restart;
  double stop_at = NAN, restart_at = NAN, downtime = NAN;
  double temp_before = NAN, temp_after = NAN;  // oil temperature [degC] before and after
};

// The evaluation's conditions in run order: healthy_runs healthy runs, then runs_per_leak leak
// runs per leak size, each with the options' effects, then sensor_fault_runs SensorFaultCondition
// runs: the kinds in turn, each kind's runs alternately without and with a leak of
// kSensorFaultLeak opening during the fault.
inline constexpr double kSensorFaultLeak = 1e-12;
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
