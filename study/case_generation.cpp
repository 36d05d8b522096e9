#include "study/case_generation.hpp"

#include <fmt/format.h>

#include <utility>

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

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};

}  // namespace

std::vector<Condition> plan_conditions(const EvaluationOptions& options) {
  std::vector<Condition> plan;
  for (int i = 0; i < options.healthy_runs; ++i) {
    plan.push_back({HealthyCondition{options.healthy_seconds}, options.effects});
  }
  for (double leak : options.leak_sizes) {
    for (int i = 0; i < options.runs_per_leak; ++i) {
      plan.push_back({LeakCondition{leak, options.after_onset_seconds}, options.effects});
    }
  }
  return plan;
}

std::uint64_t simulation_seed(std::uint64_t seed, int id) {
  return seed * 100003 + static_cast<std::uint64_t>(id);
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
