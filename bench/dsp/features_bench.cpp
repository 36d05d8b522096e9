// Streaming feature throughput (db8, level 2, window 400, step 20) for 1 and 64 channels
// (StreamingFeatures, one instant per call) and for 1 channel in blocks (BlockFeatures), against
// a naive full recomputation of every window by the same library. Items are samples
// (one channel's value at one instant), so items_per_second is samples/s summed over channels.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>
#include <vector>

#include "dsp/block_features.hpp"
#include "dsp/dwt.hpp"
#include "dsp/streaming_features.hpp"
#include "dsp/wavelet.hpp"

namespace {

using leakmon::dsp::FeatureParams;

constexpr std::size_t kInstants = 20000;  // samples per channel per iteration

// Instant-major, as the acquisition loop delivers them: kInstants rows of `channels` values.
std::vector<double> pressures(std::size_t channels) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 2e4);
  std::vector<double> x(kInstants * channels);
  for (auto& v : x) v = 8.65e6 + noise(rng);
  return x;
}

void BM_StreamingFeatures(benchmark::State& state) {
  const auto channels = static_cast<std::size_t>(state.range(0));
  FeatureParams params;
  params.step = static_cast<std::size_t>(state.range(1));
  const auto x = pressures(channels);
  leakmon::dsp::StreamingFeatures stream(params, channels);
  double sink = 0.0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < kInstants; ++i) {
      if (stream.push(std::span<const double>(x).subspan(i * channels, channels))) {
        sink += stream.latest()[0].rms;
      }
    }
  }
  benchmark::DoNotOptimize(sink);
  state.counters["incremental"] = stream.incremental() ? 1 : 0;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kInstants * channels));
}
BENCHMARK(BM_StreamingFeatures)
    ->ArgNames({"channels", "step"})
    ->Args({1, 20})
    ->Args({64, 20})
    ->Args({1, 10})  // phase-changing step: the full-recomputation fallback
    ->Unit(benchmark::kMillisecond);

// One channel through BlockFeatures (kLanes windows at a time), `block` samples per call: the
// whole run (offline analysis of a capture), or short blocks such as an acquisition loop's.
void BM_BlockFeatures(benchmark::State& state) {
  FeatureParams params;
  params.step = static_cast<std::size_t>(state.range(0));
  const auto block = static_cast<std::size_t>(state.range(1));
  const auto x = pressures(1);
  leakmon::dsp::BlockFeatures features(params);
  double sink = 0.0;
  for (auto _ : state) {
    for (std::size_t from = 0; from < kInstants; from += block) {
      features.push_block(
          std::span<const double>(x).subspan(from, std::min(block, kInstants - from)),
          [&](const leakmon::dsp::WindowFeature& f) { sink += f.feature.rms; });
    }
  }
  benchmark::DoNotOptimize(sink);
  state.counters["incremental"] = features.incremental() ? 1 : 0;
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kInstants));
}
BENCHMARK(BM_BlockFeatures)
    ->ArgNames({"step", "block"})
    ->Args({20, kInstants})
    ->Args({20, 160})        // 8 hops: one batch of kLanes windows per call
    ->Args({20, 20})         // one window per call: 1 of the kLanes lanes used
    ->Args({10, kInstants})  // phase-changing step: StreamingFeatures, one sample at a time
    ->Unit(benchmark::kMillisecond);

// Every window recomputed from scratch: the whole wavedec to `level` for each channel's window.
void BM_NaiveRecompute(benchmark::State& state) {
  const auto channels = static_cast<std::size_t>(state.range(0));
  const FeatureParams params;
  const auto x = pressures(channels);
  leakmon::dsp::DetailTransform transform(params.window, leakmon::dsp::wavelet(params.wavelet),
                                          params.mode, params.level);
  std::vector<double> window(params.window);
  double sink = 0.0;
  for (auto _ : state) {
    for (std::size_t start = 0; start + params.window <= kInstants; start += params.step) {
      for (std::size_t c = 0; c < channels; ++c) {
        for (std::size_t i = 0; i < params.window; ++i) window[i] = x[(start + i) * channels + c];
        double energy = 0.0;
        for (double d : transform.detail(window)) energy += d * d;
        sink += energy;
      }
    }
  }
  benchmark::DoNotOptimize(sink);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kInstants * channels));
}
BENCHMARK(BM_NaiveRecompute)
    ->ArgNames({"channels"})
    ->Arg(1)
    ->Arg(64)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
