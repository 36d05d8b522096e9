// Ring buffer throughput: one producer and one consumer thread moving daemon Samples (the real
// payload, ~300 bytes) and plain 8-byte values, as rigtorp/SPSCQueue measures its queue.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <thread>

#include "realtime/sample.hpp"
#include "realtime/spsc_ring.hpp"

namespace {

using leakmon::realtime::Sample;
using leakmon::realtime::SpscRing;

template <typename T>
void transfer(benchmark::State& state) {
  const auto capacity = static_cast<std::size_t>(state.range(0));
  constexpr std::int64_t kBatch = 100000;
  for (auto _ : state) {
    SpscRing<T> ring(capacity);
    std::thread consumer([&] {
      T value{};
      for (std::int64_t received = 0; received < kBatch;) {
        if (ring.try_pop(value)) ++received;
      }
      benchmark::DoNotOptimize(value);
    });
    T value{};
    for (std::int64_t sent = 0; sent < kBatch;) {
      if (ring.try_push(value)) ++sent;
    }
    consumer.join();
  }
  state.SetItemsProcessed(state.iterations() * kBatch);
  state.SetBytesProcessed(state.iterations() * kBatch * static_cast<std::int64_t>(sizeof(T)));
}

void push_pop_same_thread(benchmark::State& state) {
  SpscRing<Sample> ring(1024);
  Sample sample;
  for (auto _ : state) {
    const bool pushed = ring.try_push(sample);
    const bool popped = ring.try_pop(sample);
    benchmark::DoNotOptimize(pushed && popped);
    benchmark::DoNotOptimize(sample);
  }
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK(transfer<Sample>)->Arg(64)->Arg(8192)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(transfer<std::uint64_t>)
    ->Arg(64)
    ->Arg(8192)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(push_pop_same_thread);
BENCHMARK_MAIN();
