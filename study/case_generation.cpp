#include "study/case_generation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "sim/rig_draw.hpp"

namespace leakmon::study {
namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// A rig drawn across MODEL.md's calibration spread and the load range.
sim::Scenario draw_rig(std::mt19937_64& rng, int id, std::uint64_t seed, double duration,
                       const std::vector<std::string>& effects) {
  sim::Scenario s = sim::preset("healthy", seed);
  s.name = fmt::format("evaluate-{}", id);
  s.origin = fmt::format("leakmon evaluate run {}", id);
  s.controller = id % 2 == 0 ? sim::ControllerKind::basic : sim::ControllerKind::fault_tolerant;
  s.duration_s = duration;
  s.params.K_s = uniform(rng, 40e3, 120e3);
  s.params.beta *= uniform(rng, 0.75, 1.25);
  s.params.Kv *= uniform(rng, 0.9, 1.1);
  s.params.m *= uniform(rng, 0.8, 1.2);
  s.params.b *= uniform(rng, 0.7, 1.3);
  const double amplitude = uniform(rng, 0.6, 1.0);  // smaller steps excite the index less
  s.reference.amp_min *= amplitude;
  s.reference.amp_max *= amplitude;
  for (const auto& effect : effects) s.effects.enable(effect);
  return s;
}

// One fault of p1, p2 or x of kind `kind` (drawn when < 0; 0 frozen, 1 saturated high, 2 saturated
// low, 3 spikes, 4 dropout to zero, 5 dropout to gaps), 10-60 s, starting 10 s or more after `from`
// and ending 10 s or more before `to` where there is room.
void draw_sensor_fault(std::mt19937_64& rng, int kind, double from, double to, RunSpec& run) {
  sim::SensorFault fault;
  const sim::SensorChannel channels[] = {sim::SensorChannel::p1, sim::SensorChannel::p2,
                                         sim::SensorChannel::x};
  fault.channel = channels[std::uniform_int_distribution<int>(0, 2)(rng)];
  if (kind < 0) kind = std::uniform_int_distribution<int>(0, 5)(rng);
  fault.kind = kind == 0   ? sim::SensorFault::Kind::frozen
               : kind <= 2 ? sim::SensorFault::Kind::saturated
               : kind == 3 ? sim::SensorFault::Kind::spikes
                           : sim::SensorFault::Kind::dropout;
  fault.high = kind == 1;
  fault.gap = kind == 5;
  fault.duration_s = uniform(rng, 10.0, 60.0);
  fault.start_s = uniform(rng, from + 10.0, std::max(from + 10.0, to - fault.duration_s - 10.0));
  // Spikes: a few per minute, MODEL.md; off by MPa on a pressure, by millimetres on x.
  fault.rate_per_min = uniform(rng, 3.0, 10.0);
  fault.magnitude =
      fault.channel == sim::SensorChannel::x ? uniform(rng, 2e-3, 1e-2) : uniform(rng, 1e6, 4e6);
  run.fault_channel = std::string(sim::to_string(fault.channel));
  run.fault_kind = std::string(sim::to_string(fault.kind));
  run.fault_variant = run.fault_kind;
  if (fault.kind == sim::SensorFault::Kind::saturated)
    run.fault_variant += fault.high ? "_high" : "_low";
  if (fault.kind == sim::SensorFault::Kind::dropout)
    run.fault_variant += fault.gap ? "_gap" : "_zero";
  run.fault_start = fault.start_s;
  run.fault_end = fault.start_s + fault.duration_s;
  run.fault_seen = fault.start_s;
  run.scenario.faults.push_back(fault);
}

// Whether a leak in `phase` can be seen: not in a hold whose load |K_s X| / A stays below
// kJudgeableLoad.
bool judgeable(const sim::Phase& phase, const sim::Parameters& params) {
  return phase.kind != sim::PhaseKind::hold ||
         std::abs(params.K_s * phase.X) / params.A() >= kJudgeableLoad;
}

// The truth of a program run: its phases where they sit in the run.
void describe_program(RunSpec& run) {
  const sim::Scenario& s = run.scenario;
  const auto spans = sim::phase_spans(s.program, s.duration_s);
  run.phases.clear();
  for (std::size_t i = 0; i < spans.size(); ++i) {
    const sim::Phase& phase = s.program[i];
    run.phases.push_back(
        {phase.kind, spans[i].start, spans[i].end, judgeable(phase, s.params), phase.notation()});
  }
}

// A program (MODEL.md "Test programs") the run's rig can run. On the paper's rig as drawn. On
// another rig its positions and amplitudes scale as the rig's steps do (a rig whose valve or load
// cannot make the paper's 50 mm moves makes smaller ones), and it is drawn again while the rig
// cannot run it (sim::check_viability on the program with each phase cut to kViabilitySeconds;
// after kProgramDraws tries at half the amplitudes, and so on).
std::vector<sim::Phase> draw_program_for_rig(std::mt19937_64& rng, const EvaluationOptions& options,
                                             std::optional<sim::PhaseKind> leak_kind,
                                             const sim::Scenario& s, int& leak_phase) {
  if (options.rigs != "other") {
    return sim::draw_program(rng, options.time_scale, leak_kind, leak_phase);
  }
  constexpr int kProgramDraws = 6;
  constexpr double kViabilitySeconds = 20.0;
  double scale = s.reference.amp_max / sim::ReferenceSettings{}.amp_max;
  sim::Scenario trial = s;
  trial.effects = sim::Effects{};
  for (int attempt = 1;; ++attempt) {
    std::vector<sim::Phase> program =
        sim::draw_program(rng, options.time_scale, leak_kind, leak_phase);
    for (auto& phase : program) {
      phase.X *= scale;
      phase.A *= scale;
    }
    trial.program = program;
    for (auto& phase : trial.program)
      phase.duration_s = std::min(phase.duration_s, kViabilitySeconds);
    trial.duration_s = sim::program_seconds(trial.program);
    if (attempt >= 4 * kProgramDraws || sim::check_viability(trial, trial.duration_s).ok) {
      return program;
    }
    if (attempt % kProgramDraws == 0) scale *= 0.5;
  }
}

// programs: a random program on the stationary rig. A healthy run lasts as long as its program;
// a leak run opens its leak inside the phase of the planned kind, 20 s or more after learning,
// in the phase's first part (detect_within before its end where the phase is that long), and
// runs on for the condition's time after the onset, or to detect_within + 30 s after the phase's
// end when the phase cannot be judged.
void apply_program(std::mt19937_64& rng, const EvaluationOptions& options, RunSpec& run) {
  sim::Scenario& s = run.scenario;
  const auto* leak = std::get_if<LeakCondition>(&run.condition.kind);
  std::optional<sim::PhaseKind> leak_kind;
  if (leak && run.leak > 0.0) {
    leak_kind = leak->phase
                    ? *leak->phase
                    : sim::kPhaseKinds[std::uniform_int_distribution<std::size_t>(0, 4)(rng)];
  }
  int j = -1;
  s.program = draw_program_for_rig(rng, options, leak_kind, s, j);
  s.duration_s = sim::program_seconds(s.program);
  if (j >= 0) {
    const auto at = static_cast<std::size_t>(j);
    auto spans = sim::phase_spans(s.program, sim::program_seconds(s.program));
    const double length = spans[at].end - spans[at].start;
    const double lo =
        std::max(spans[at].start + std::min(10.0, 0.1 * length), run.monitor_from + 20.0);
    if (lo > spans[at].end - 10.0) {
      // A short phase right after learning: lengthened so the leak opens inside it.
      s.program[at].duration_s += lo - (spans[at].end - 10.0);
      spans = sim::phase_spans(s.program, sim::program_seconds(s.program));
    }
    const double hi = std::max(lo, spans[at].end - options.detect_within);
    run.onset = uniform(rng, lo, hi);
    run.leak_phase = j;
    double end = run.onset + leak->after_onset_seconds;
    if (!judgeable(s.program[at], s.params)) {
      end = std::max(end, spans[at].end + options.detect_within + 30.0);
    }
    s.duration_s = end;
    s.effects.internal_leakage->onset_s = run.onset;
  }
  describe_program(run);
}

// Draws the operating condition's parameters onto the scenario (MODEL.md "Drifting operating
// conditions" and "Sensor faults"), from its own stream so the rig draws of the other runs stay
// as they are. `healthy_from`..`healthy_to` is where a sensor fault may sit.
void apply_operating(const std::string& operating, std::mt19937_64& rng, double healthy_from,
                     double healthy_to, const EvaluationOptions& options, RunSpec& run) {
  if (operating == "stationary") return;
  if (operating == "programs") {
    apply_program(rng, options, run);
    return;
  }
  sim::Scenario& s = run.scenario;
  s.record.temp = true;
  s.record.ps = true;
  const int grades[] = {32, 46, 68};
  s.conditions.oil = *sim::Oil::iso_vg(grades[std::uniform_int_distribution<int>(0, 2)(rng)]);
  sim::TemperatureProfile profile;
  if (operating == "warmup") {
    profile.kind = sim::TemperatureProfile::Kind::warm_up;
    profile.T0 = uniform(rng, 15.0, 35.0);
    profile.T_work = uniform(rng, 45.0, 55.0);
    profile.tau_s = uniform(rng, 300.0, 1200.0);
    s.conditions.temperature = profile;
    if (run.leak > 0.0) {
      // The leak opens anywhere from early in the warm-up to well after it (1.5 time constants).
      const double after = s.duration_s - run.onset;
      run.onset = healthy_from + uniform(rng, 20.0, 20.0 + 1.5 * profile.tau_s);
      s.duration_s = run.onset + after;
      s.effects.internal_leakage->onset_s = run.onset;
    }
  } else if (operating == "cooler" || operating == "wear") {
    profile.kind = sim::TemperatureProfile::Kind::cooler;
    profile.T_work = uniform(rng, 45.0, 55.0);
    profile.amplitude = uniform(rng, 1.0, 4.0);
    profile.period_s = uniform(rng, 300.0, 1200.0);
    // The cycle's phase at the start of learning is random too.
    profile.cooler_start_s = -uniform(rng, 0.0, profile.period_s);
    s.conditions.temperature = profile;
    if (operating == "wear" && run.leak > 0.0) {
      // A seal that wears (MODEL.md "Test programs"): C_L from 0 at the onset to 1e-12..5e-12
      // over 10 min to 4 h (log-uniform), the run going on after it for the condition's time.
      run.leak = uniform(rng, 1e-12, 5e-12) * run.valve_scale;
      run.wear_seconds =
          std::exp(uniform(rng, std::log(600.0), std::log(14400.0))) * options.time_scale;
      const double after = s.duration_s - run.onset;
      s.effects.internal_leakage = sim::InternalLeakage{run.leak, run.onset, run.wear_seconds};
      s.duration_s = run.onset + run.wear_seconds + after;
    }
  } else if (operating == "supply") {
    const int changes = std::uniform_int_distribution<int>(1, 2)(rng);
    double t = healthy_from;
    for (int i = 0; i < changes && t < healthy_to; ++i) {
      t = uniform(rng, t + 10.0, std::max(t + 10.0, healthy_to - 30.0));
      const double ramp = uniform(rng, 0.0, 5.0);
      // MODEL.md's 13-20 MPa around the paper's 17.2, as that share of another rig's supply.
      const double share = s.params.ps / sim::Parameters{}.ps;
      s.conditions.supply.push_back({t, share * uniform(rng, 13e6, 20e6), ramp});
      t += ramp;
    }
  } else if (operating == "sensor-faults" && !run.sensor_fault_run) {
    draw_sensor_fault(rng, -1, healthy_from, healthy_to, run);
  } else if (operating == "restart") {
    // Learning and a monitored stretch at a steady temperature, then the daemon stops and its
    // state is saved; the rig runs on while it is down, the oil warming or cooling by 1-5 K (a
    // rig that was switched off cools, one that kept working may warm) and, in a leak run, the
    // leak opening; the daemon restarts on the rig as it is then.
    const double temp_before = uniform(rng, 40.0, 50.0);
    const double change = (rng() % 2 == 0 ? 1.0 : -1.0) * uniform(rng, 1.0, 5.0);
    profile.kind = sim::TemperatureProfile::Kind::constant;
    profile.T_work = temp_before;
    s.conditions.temperature = profile;
    run.temp_before = temp_before;
    run.temp_after = temp_before + change;
    run.stop_at = healthy_from + uniform(rng, 30.0, 120.0);
    run.downtime = uniform(rng, 10.0, 1800.0);
    run.restart_at = run.stop_at + run.downtime;
    sim::Scenario after = s;
    after.seed = s.seed ^ 0x3c6ef372fe94f82bULL;  // the rig's noise and moves go on, not repeat
    after.conditions.temperature->T_work = run.temp_after;
    after.name += "-restarted";
    if (run.leak > 0.0) {
      after.effects.internal_leakage = sim::InternalLeakage{run.leak, 0.0, 0.0};
      after.duration_s = options.after_onset_seconds;
      run.onset = run.restart_at;
    } else {
      after.effects.internal_leakage.reset();
      after.duration_s = options.after_restart_seconds;
    }
    s.effects.internal_leakage.reset();
    s.duration_s = run.stop_at;
    run.after_restart = after;
  }
}

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
// Clang before 17 does not deduce an aggregate's template arguments (C++20's P1816) without it.
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

std::vector<Condition> plan_conditions(const EvaluationOptions& options) {
  std::vector<Condition> plan;
  // Each kind of run cycles through the operating conditions, so every condition gets its share
  // of healthy time and of every leak size.
  const auto& operating = options.conditions;
  auto pick = [&](int i) {
    return operating.empty() ? std::string("stationary")
                             : operating[static_cast<std::size_t>(i) % operating.size()];
  };
  for (int i = 0; i < options.healthy_runs; ++i) {
    plan.push_back({HealthyCondition{options.healthy_seconds}, options.effects, pick(i)});
  }
  std::size_t program_leaks = 0;  // leak runs under `programs`: the phase kinds in turn
  for (double leak : options.leak_sizes) {
    for (int i = 0; i < options.runs_per_leak; ++i) {
      LeakCondition condition{leak, options.after_onset_seconds, std::nullopt};
      if (pick(i) == "programs") {
        condition.phase = sim::kPhaseKinds[program_leaks++ % sim::kPhaseKinds.size()];
      }
      plan.push_back({condition, options.effects, pick(i)});
    }
  }
  for (int i = 0; i < options.sensor_fault_runs; ++i) {
    plan.push_back({SensorFaultCondition{(i / 6) % 2 == 1 ? kSensorFaultLeak : 0.0,
                                         options.after_fault_seconds, i % 6},
                    options.effects, "sensor-faults"});
  }
  return plan;
}

double RunSpec::leak_at(double t) const {
  if (leak <= 0.0 || t < onset) return 0.0;
  if (!wear_run() || wear_seconds <= 0.0) return leak;
  return leak * std::min(1.0, (t - onset) / wear_seconds);
}

int RunSpec::phase_at(double t) const {
  for (std::size_t i = 0; i < phases.size(); ++i) {
    if (t >= phases[i].start && t < phases[i].end) return static_cast<int>(i);
  }
  // The run's last instant belongs to the last phase reached.
  for (std::size_t i = phases.size(); i-- > 0;) {
    if (phases[i].start < phases[i].end) return t == phases[i].end ? static_cast<int>(i) : -1;
  }
  return -1;
}

double RunSpec::detection_deadline(double detect_within) const {
  const int i = phase_at(onset);
  if (i < 0 || phases[static_cast<std::size_t>(i)].judgeable) return onset + detect_within;
  return phases[static_cast<std::size_t>(i)].end + detect_within;
}

std::uint64_t simulation_seed(std::uint64_t seed, int id) {
  return seed * 100003 + static_cast<std::uint64_t>(id);
}

// Seeds the rig drawer apart from the simulation's own streams.
constexpr std::uint64_t kOtherRigSeed = 0x6f746865722d7267ULL;  // "other-rg"

void use_other_rig(RunSpec& run) {
  sim::Scenario& s = run.scenario;
  const sim::OtherRig other = sim::draw_other_rig(s.seed ^ kOtherRigSeed, s.controller);
  s.rig = other.rig;
  s.params = other.rig.params;
  s.conditions.oil = other.rig.oil;
  s.reference = other.reference;
  s.sensors = other.sensors;
  s.name += "-other-rig";
  run.valve_scale = s.params.Kv / kPaperValveCoefficient;
  if (run.leak > 0.0) {
    run.leak *= run.valve_scale;
    if (s.effects.internal_leakage) s.effects.internal_leakage->C_L = run.leak;
  }
}

RunSpec generate_case(int id, std::uint64_t seed, const Condition& condition,
                      std::mt19937_64& rig_draws, const EvaluationOptions& options) {
  RunSpec run;
  run.id = id;
  run.condition = condition;
  run.monitor_from = options.settle_seconds + options.learn_seconds + 1.0;
  std::visit(Overloaded{
                 [&](const HealthyCondition& healthy) {
                   run.scenario = draw_rig(rig_draws, id, seed, healthy.seconds, condition.effects);
                 },
                 [&](const SensorFaultCondition&) {
                   run.scenario =
                       draw_rig(rig_draws, id, seed, run.monitor_from, condition.effects);
                 },
                 [&](const LeakCondition& leak) {
                   run.leak = leak.coefficient;
                   // A healthy stretch after learning (false alarms count there too), then the
                   // leak.
                   run.onset = run.monitor_from + uniform(rig_draws, 20.0, 60.0);
                   run.scenario = draw_rig(rig_draws, id, seed,
                                           run.onset + leak.after_onset_seconds, condition.effects);
                   run.scenario.effects.internal_leakage =
                       sim::InternalLeakage{leak.coefficient, run.onset, 0.0};
                 },
             },
             condition.kind);
  if (options.rigs == "other") use_other_rig(run);
  std::mt19937_64 operating_draws(seed ^ 0x6a09e667f3bcc909ULL);
  run.sensor_fault_run = std::holds_alternative<SensorFaultCondition>(condition.kind);
  apply_operating(condition.operating, operating_draws, run.monitor_from,
                  std::min(run.onset, run.scenario.duration_s), options, run);
  if (const auto* fault = std::get_if<SensorFaultCondition>(&condition.kind)) {
    // A fault 10-40 s into monitoring; in a leak run the leak opens while it lasts.
    const double start = run.monitor_from + uniform(operating_draws, 0.0, 30.0);
    draw_sensor_fault(operating_draws, fault->kind, start, start, run);
    if (fault->coefficient > 0.0) {
      run.leak = fault->coefficient;
      run.onset = uniform(operating_draws, run.fault_start, run.fault_end);
      run.scenario.effects.internal_leakage = sim::InternalLeakage{run.leak, run.onset, 0.0};
    }
    run.scenario.duration_s = run.fault_end + fault->after_fault_seconds;
  }
  return run;
}

std::vector<RunSpec> draw_runs(const EvaluationOptions& options) {
  std::mt19937_64 rig_draws(options.seed);
  std::vector<RunSpec> runs;
  int id = 0;
  for (const Condition& condition : plan_conditions(options)) {
    runs.push_back(
        generate_case(id, simulation_seed(options.seed, id), condition, rig_draws, options));
    ++id;
  }
  return runs;
}

}  // namespace leakmon::study
