// Cost of one Detector::update() (the worker calls it once per hop, every 40 ms per actuator),
// measured after learning, on the synthetic rig of the unit tests.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "detect/factory.hpp"
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

BENCHMARK_CAPTURE(detector_update, paper, std::string("paper"));
BENCHMARK_CAPTURE(detector_update, index_cusum, std::string("index_cusum"));
BENCHMARK_CAPTURE(detector_update, flow_balance, std::string("flow_balance"));
BENCHMARK_CAPTURE(detector_update, fused, std::string("fused"));

}  // namespace

BENCHMARK_MAIN();
