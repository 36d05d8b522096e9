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
// switched on for `after_onset_seconds`. Under the `programs` condition the leak opens inside a
// phase of kind `phase` (the plan cycles through the kinds).
struct LeakCondition {
  double coefficient = 0.0;
  double after_onset_seconds = 0.0;
  std::optional<sim::PhaseKind> phase = std::nullopt;
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

// Below this load |K_s X| / A a hold gives nothing to judge: the leak's flow C_L (p1 - p2)
// vanishes with p1 - p2 (MODEL.md "Test programs": about 1 MPa on this rig).
inline constexpr double kJudgeableLoad = 1e6;  // Pa

// A phase of a run's test program where it sits in the run, as the truth scores it.
struct ProgramPhase {
  sim::PhaseKind kind = sim::PhaseKind::steps;
  double start = 0.0, end = 0.0;  // [s]; the last phase reached ends with the run
  // False for a hold whose load |K_s X| / A stays below kJudgeableLoad: a leak opening there is
  // to be found within the window of the next phase's start instead.
  bool judgeable = true;
  std::string notation;  // "hold 0.02", "sine 0.5 0.02", ... (sim::Phase::notation)
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
  // programs: the phases of the run's test program (scenario.program) where they sit in the run
  // (empty: the paper's steps), and the one the leak opens in (-1: none).
  std::vector<ProgramPhase> phases;
  int leak_phase = -1;
  // wear: C_L grows linearly from 0 at `onset` to `leak` over `wear_seconds` (NaN: a leak that
  // opens at once). Scored by the C_L at which it is found (write_condition_summaries), not in
  // the generic tables.
  double wear_seconds = NAN;
  bool wear_run() const { return !std::isnan(wear_seconds); }
  // The run's valve against the paper's (Kv / kPaperValveCoefficient on another rig, 1 on the
  // paper's): leak sizes are drawn and scored as that share of the valve's flow.
  double valve_scale = 1.0;
  // The C_L [m^3/(s Pa)] in force at t.
  double leak_at(double t) const;
  // Index into `phases` of the phase that holds t (-1 without a program or outside it).
  int phase_at(double t) const;
  // The latest raise that finds the leak: detect_within after the onset, or after the next
  // phase's start when the leak opens in a phase that cannot be judged.
  double detection_deadline(double detect_within) const;
};

// The evaluation's conditions in run order: healthy_runs healthy runs, then runs_per_leak leak
// runs per leak size, each with the options' effects, then sensor_fault_runs SensorFaultCondition
// runs: the kinds in turn, each kind's runs alternately without and with a leak of
// kSensorFaultLeak opening during the fault. Leak runs under `programs` take the phase kinds in
// turn (steps, hold, sine, sweep, triangle) for the phase their leak opens in.
inline constexpr double kSensorFaultLeak = 1e-12;
std::vector<Condition> plan_conditions(const EvaluationOptions& options);

// Seed of run `id`'s simulation (noise, reference) in a study with master seed `seed`.
std::uint64_t simulation_seed(std::uint64_t seed, int id);

// MODEL.md's Kv of the paper's valve: leak sizes on other rigs are stated relative to it.
inline constexpr double kPaperValveCoefficient = 3.39e-7;

// The case generator's hook for `--rigs other`: the run's rig (description, plant, oil,
// reference, transducers) becomes one drawn by sim::draw_other_rig for the run's controller,
// seeded by the run's seed; its leak (and onset, duration, effects) stays, scaled to the valve.
void use_other_rig(RunSpec& run);

// The scenario of run `id` under `condition`. The rig (controller, spring, beta, Kv, m, b,
// reference amplitude) and the onset are drawn from `rig_draws`, the study's one stream shared
// by all runs in order, so a master seed reproduces every run; `seed` seeds the simulation.
RunSpec generate_case(int id, std::uint64_t seed, const Condition& condition,
                      std::mt19937_64& rig_draws, const EvaluationOptions& options);

// plan_conditions -> generate_case for every run, from the master seed.
std::vector<RunSpec> draw_runs(const EvaluationOptions& options);

}  // namespace leakmon::study
