// Cost of one Detector::update() (the worker calls it once per hop, every 40 ms per actuator),
// measured after learning, on the synthetic rig of the unit tests.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "detect/factory.hpp"
#include "sim/simulate.hpp"
#include "tests/detect/synthetic_pressures.hpp"
#include "tests/detect/synthetic_rig.hpp"
#include "tests/support/hop_observation.hpp"

namespace {

namespace sim = leakmon::sim;
namespace capture = leakmon::capture;

void detector_update(benchmark::State& state, const std::string& kind) {
  auto detector = leakmon::detect::make_detector(kind, {true, true, true, true}, 0.04, nullptr);
  leakmon::test::SyntheticRig rig;
  rig.onset = 200.0;
  rig.leak = 1e-12;
  std::vector<leakmon::detect::Observation> stream;
  for (int i = 0; i < 20000; ++i) stream.push_back(rig.next());
  std::size_t next = 0;
  for (; next < 5000; ++next) detector->update(stream[next]);  // past learning
  for (auto _ : state) {
    benchmark::DoNotOptimize(detector->update(stream[next]));
    if (++next == stream.size()) next = 5000;
  }
}

// detail_xcorr filters the hop's 20 samples of each chamber itself (synthetic_pressures.hpp).
void detail_xcorr_update(benchmark::State& state, bool both_chambers) {
  const leakmon::detect::AvailableSignals signals{true, both_chambers, false, false};
  auto detector = leakmon::detect::make_detector("detail_xcorr", signals, 0.04, nullptr);
  leakmon::test::SyntheticPressures rig;
  constexpr std::size_t kHops = 6000;
  std::vector<leakmon::detect::Observation> stream;
  std::vector<double> samples;
  samples.reserve(2 * kHops * rig.kHop);
  for (std::size_t i = 0; i < kHops; ++i) {
    stream.push_back(rig.next());
    samples.insert(samples.end(), rig.p1.begin(), rig.p1.end());
    samples.insert(samples.end(), rig.p2.begin(), rig.p2.end());
  }
  for (std::size_t i = 0; i < kHops; ++i) {
    const double* hop = samples.data() + 2 * i * rig.kHop;
    stream[i].p1_samples = {hop, rig.p1.size()};
    stream[i].p2_samples = both_chambers ? std::span<const double>(hop + rig.kHop, rig.p2.size())
                                         : std::span<const double>();
  }
  std::size_t next = 0;
  for (; next < 3000; ++next) detector->update(stream[next]);  // past learning
  for (auto _ : state) {
    benchmark::DoNotOptimize(detector->update(stream[next]));
    if (++next == stream.size()) next = 3000;
  }
}

// flow_law (the default with u and x) integrates the valve's flow sample by sample, so it runs on
// the simulated rig's own samples (the paper's steps, 300 s, a 1e-12 leak from 200 s): the hops
// as the worker forms them, means and the hop's 20 samples per signal.
void flow_law_update(benchmark::State& state) {
  constexpr std::size_t kStep = 20;
  sim::Scenario scenario;
  scenario.duration_s = 300.0;
  scenario.seed = 5;
  sim::InternalLeakage leak;
  leak.C_L = 1e-12;
  leak.onset_s = 200.0;
  scenario.effects.internal_leakage = leak;
  const capture::Capture capture = sim::simulate(scenario);
  std::vector<leakmon::detect::Observation> stream;
  for (std::size_t start = 0; start + kStep <= capture.rows(); start += kStep) {
    stream.push_back(leakmon::test::hop_observation(capture, start, kStep));
  }
  auto detector =
      leakmon::detect::make_detector("flow_law", {true, true, true, true}, 0.04, nullptr);
  const std::size_t learned = stream.size() / 2;  // 150 s: past learning on the steps
  std::size_t next = 0;
  for (; next < learned; ++next) detector->update(stream[next]);
  for (auto _ : state) {
    benchmark::DoNotOptimize(detector->update(stream[next]));
    if (++next == stream.size()) next = learned;
  }
}

BENCHMARK_CAPTURE(detector_update, paper, std::string("paper"));
BENCHMARK_CAPTURE(detector_update, index_cusum, std::string("index_cusum"));
BENCHMARK_CAPTURE(detector_update, flow_balance, std::string("flow_balance"));
BENCHMARK_CAPTURE(detector_update, fused, std::string("fused"));
BENCHMARK(flow_law_update);
BENCHMARK_CAPTURE(detail_xcorr_update, detail_xcorr, true);
BENCHMARK_CAPTURE(detail_xcorr_update, detail_xcorr_p1, false);

}  // namespace

BENCHMARK_MAIN();
