// CAN frames per second decoded from a candump log: the parser alone, the signal decoding
// alone, and both together as the canlog driver replays them (docs/performance.md, "Field
// drivers"). The log is the rig's traffic: two frames per 2 ms sample carrying p1, p2 (Intel)
// and x (Motorola, signed) and u.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>
#include <vector>

#include "io/can/frame_decoder.hpp"
#include "io/canlog/candump.hpp"

namespace {

using namespace leakmon::io;

std::string rig_log(int samples) {
  std::string log;
  char line[96];
  for (int k = 0; k < samples; ++k) {
    const unsigned p1 = 17300 + (k * 37) % 400, p2 = 17300 - (k * 53) % 400;
    const long long us = 1763740800LL * 1000000 + k * 2000LL;
    std::snprintf(line, sizeof line, "(%lld.%06lld) can0 101#%02X%02X%02X%02X\n", us / 1000000,
                  us % 1000000, p1 & 0xFF, p1 >> 8, p2 & 0xFF, p2 >> 8);
    log += line;
    std::snprintf(line, sizeof line, "(%lld.%06lld) can0 102#%08X%04X\n", (us + 200) / 1000000,
                  (us + 200) % 1000000, static_cast<unsigned>(k * 13), 1500U);
    log += line;
  }
  return log;
}

std::vector<can::SignalDef> rig_signals() {
  auto signal = [](const char* channel, std::uint32_t id, unsigned start, unsigned length,
                   can::ByteOrder order, bool is_signed) {
    can::SignalDef d;
    d.channel = channel;
    d.layout.id = id;
    d.layout.start_bit = start;
    d.layout.length = length;
    d.layout.byte_order = order;
    d.layout.is_signed = is_signed;
    d.layout.factor = 500;
    d.max_age_ns = 20'000'000;
    return d;
  };
  return {signal("p1", 0x101, 0, 16, can::ByteOrder::intel, false),
          signal("p2", 0x101, 16, 16, can::ByteOrder::intel, false),
          signal("x", 0x102, 7, 32, can::ByteOrder::motorola, true),
          signal("u", 0x102, 32, 16, can::ByteOrder::intel, true)};
}

void BM_CandumpParse(benchmark::State& state) {
  const std::string log = rig_log(5000);
  std::vector<std::string_view> lines;
  for (std::size_t start = 0; start < log.size();) {
    const std::size_t end = log.find('\n', start);
    lines.emplace_back(log.data() + start, end - start);
    start = end + 1;
  }
  canlog::LogRecord record;
  canlog::ParseProblem problem;
  for (auto _ : state) {
    for (auto line : lines) {
      benchmark::DoNotOptimize(canlog::parse_candump_line(line, record, problem));
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(lines.size()));
}
BENCHMARK(BM_CandumpParse);

void BM_SignalDecode(benchmark::State& state) {
  can::FrameDecoder decoder(rig_signals());
  std::vector<can::CanFrame> frames;
  for (const auto& logged : canlog::parse_candump_text(rig_log(5000), "bench.log").frames) {
    frames.push_back(logged.frame);
  }
  std::vector<double> values(4);
  std::int64_t t = 0;
  for (auto _ : state) {
    for (const auto& f : frames) decoder.apply(f, t += 1'000'000);
    decoder.sample(values, t);
    benchmark::DoNotOptimize(values.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(frames.size()));
}
BENCHMARK(BM_SignalDecode);

void BM_ParseAndDecode(benchmark::State& state) {
  const std::string log = rig_log(5000);
  can::FrameDecoder decoder(rig_signals());
  canlog::LogRecord record;
  canlog::ParseProblem problem;
  std::int64_t frames = 0;
  for (auto _ : state) {
    for (std::size_t start = 0; start < log.size();) {
      const std::size_t end = log.find('\n', start);
      if (canlog::parse_candump_line(std::string_view(log).substr(start, end - start), record,
                                     problem) == canlog::LineKind::frame) {
        decoder.apply(record.frame, record.time_ns);
        ++frames;
      }
      start = end + 1;
    }
  }
  state.SetItemsProcessed(frames);
}
BENCHMARK(BM_ParseAndDecode);

}  // namespace

BENCHMARK_MAIN();
