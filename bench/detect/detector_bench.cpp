// Cost of one Detector::update() (the worker calls it once per hop, every 40 ms per actuator),
// measured after learning, on the synthetic rig of the unit tests.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "detect/factory.hpp"
#include "tests/detect/synthetic_pressures.hpp"
#include "tests/detect/synthetic_rig.hpp"

namespace {

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

BENCHMARK_CAPTURE(detector_update, paper, std::string("paper"));
BENCHMARK_CAPTURE(detector_update, index_cusum, std::string("index_cusum"));
BENCHMARK_CAPTURE(detector_update, flow_balance, std::string("flow_balance"));
BENCHMARK_CAPTURE(detector_update, fused, std::string("fused"));
BENCHMARK_CAPTURE(detail_xcorr_update, detail_xcorr, true);
BENCHMARK_CAPTURE(detail_xcorr_update, detail_xcorr_p1, false);

}  // namespace

BENCHMARK_MAIN();
