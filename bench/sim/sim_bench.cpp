// Simulator speed: simulated seconds per wall (CPU) second for the 600 s paper presets, one
// core, through the same Rig::step() the daemon's sim driver and the batch API use.
// Run: build/bin/sim_bench  (the counter sim_s_per_s is the real-time factor)
#include <benchmark/benchmark.h>

#include <string>

#include "sim/rig.hpp"
#include "sim/scenario.hpp"

namespace {

void run_preset(benchmark::State& state, const std::string& name) {
  const leakmon::sim::Scenario scenario = leakmon::sim::preset(name, 1);
  double checksum = 0.0;
  for (auto _ : state) {
    leakmon::sim::Rig rig(scenario);
    for (std::uint64_t k = 0; k < scenario.samples(); ++k) checksum += rig.step().p1;
    benchmark::DoNotOptimize(checksum);
  }
  state.counters["sim_s_per_s"] = benchmark::Counter(
      scenario.duration_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_PaperFig13(benchmark::State& state) { run_preset(state, "paper-fig13"); }
void BM_PaperFig16(benchmark::State& state) { run_preset(state, "paper-fig16"); }

// One 2 ms sample of the closed loop, as the daemon's in-loop driver calls it.
void BM_RigStep(benchmark::State& state) {
  leakmon::sim::Scenario scenario = leakmon::sim::preset("paper-fig13", 1);
  scenario.duration_s = 1e6;
  leakmon::sim::Rig rig(scenario);
  for (auto _ : state) benchmark::DoNotOptimize(rig.step());
}

// With every plant effect on (friction shortens the RK4 step: the costliest configuration).
void BM_RigStepAllEffects(benchmark::State& state) {
  leakmon::sim::Scenario scenario = leakmon::sim::preset("paper-fig13", 1);
  scenario.duration_s = 1e6;
  for (const auto name : leakmon::sim::Effects::names()) {
    if (name != "internal_leakage") scenario.effects.enable(name);
  }
  leakmon::sim::Rig rig(scenario);
  for (auto _ : state) benchmark::DoNotOptimize(rig.step());
}

BENCHMARK(BM_PaperFig13)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PaperFig16)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RigStep)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RigStepAllEffects)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
