// The acquisition loop's real-time thread: no heap allocation once running, every cycle
// accounted for (pushed or dropped), nothing lost between loop and worker. Under TSan in CI.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "config/yaml_reader.hpp"
#include "daemon/config.hpp"
#include "io/replay/replay_driver.hpp"
#include "io/sim/sim_driver.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/worker.hpp"
#include "realtime/acquisition_loop.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::realtime {
namespace {

std::shared_ptr<const capture::Capture> ramp_capture(std::size_t rows) {
  auto capture = std::make_shared<capture::Capture>();
  capture->path = "ramp";
  capture->columns = {"t", "p1", "p2"};
  capture->values.assign(3, {});
  for (std::size_t i = 0; i < rows; ++i) {
    capture->values[0].push_back(static_cast<double>(i) * 0.002);
    capture->values[1].push_back(8e6 + static_cast<double>(i % 50) * 1e3);
    capture->values[2].push_back(8e6 - static_cast<double>(i % 50) * 1e3);
  }
  return capture;
}

TEST(RealtimeLoop, AllocatesNothingOnItsThreadAndLosesNothing) {
  io::ReplaySettings replay_settings;
  replay_settings.name = "bench";
  replay_settings.loop = true;
  io::ReplayDriver replay(replay_settings, ramp_capture(1000));
  replay.start();
  auto sim = io::make_sim_driver(config::ConfigNode::load_string(
      "{name: rig, type: sim, scenario: healthy, seed: 3, leak: {lpm_per_mpa: 0.1, onset_s: 0.2}}",
      "test"));
  sim->start();

  SpscRing<Sample> ring(256);
  AcquisitionLoop loop(2'000'000, {&replay, sim.get()}, ring);
  ASSERT_EQ(loop.channel_count(), 2u + 6u);

  pipeline::DaemonConfig config = daemon::parse_config(config::ConfigNode::load_string(
      "drivers: [{name: bench, type: replay, path: unused.csv}, {name: rig, type: sim, "
      "scenario: healthy}]\n"
      "actuators: [{name: a, channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x}}]\n",
      "test.yaml"));
  std::vector<pipeline::ChannelRef> channels;
  for (const auto& c : replay.channels()) channels.push_back({"bench", c, std::nullopt});
  for (const auto& c : sim->channels()) channels.push_back({"rig", c, std::nullopt});
  pipeline::CollectingEventSink events;
  pipeline::Worker worker(config, {pipeline::GroupInput{"main", &ring, channels, 2'000'000}},
                          {&events});

  std::atomic<bool> stop{false};
  std::uint64_t loop_allocations = 0;
  std::thread acquisition([&] {
    make_thread_realtime(0, {});
    test::AllocationScope scope;
    loop.run(stop);
    loop_allocations = scope.count();
  });
  std::atomic<bool> stop_worker{false};
  std::thread consumer([&] {
    while (!stop_worker.load()) {
      if (worker.drain(monotonic_now_ns()) == 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
  });
  // Wait for enough cycles that the features, detector and sim have all been exercised.
  while (loop.counters().cycles.load() < 600)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  stop.store(true);
  acquisition.join();
  stop_worker.store(true);
  consumer.join();
  worker.drain(monotonic_now_ns());

  EXPECT_EQ(loop_allocations, 0u) << "the real-time loop allocated";
  const auto& counters = loop.counters();
  EXPECT_GE(counters.cycles.load(), 600u);
  EXPECT_EQ(counters.samples_pushed.load() + counters.ring_drops.load(), counters.cycles.load());
  EXPECT_EQ(worker.samples_processed(), counters.samples_pushed.load());
  EXPECT_EQ(counters.wakeup_latency.count(), counters.cycles.load());
  EXPECT_LE(counters.ring_high_water.load(), ring.capacity());
}

TEST(RealtimeLoop, FullRingDropsAndCountsInsteadOfWaiting) {
  io::ReplaySettings settings;
  settings.loop = true;
  io::ReplayDriver replay(settings, ramp_capture(100));
  replay.start();
  SpscRing<Sample> ring(8);
  AcquisitionLoop loop(1'000'000, {&replay}, ring);
  io::Tick tick;
  for (; tick.index < 20; ++tick.index) ASSERT_TRUE(loop.cycle(tick, 1));
  EXPECT_EQ(loop.counters().samples_pushed.load(), 8u);
  EXPECT_EQ(loop.counters().ring_drops.load(), 12u);
  EXPECT_EQ(loop.counters().ring_high_water.load(), 8u);
  Sample sample;
  ASSERT_TRUE(ring.try_pop(sample));
  EXPECT_EQ(sample.tick, 0u);
  EXPECT_EQ(sample.channel_count, 2u);
  EXPECT_DOUBLE_EQ(sample.values[0], 8e6);
}

TEST(RealtimeLoop, FiniteSourceEndsTheStream) {
  io::ReplaySettings settings;
  io::ReplayDriver replay(settings, ramp_capture(5));
  replay.start();
  SpscRing<Sample> ring(16);
  AcquisitionLoop loop(1'000'000, {&replay}, ring);
  std::atomic<bool> stop{false};
  loop.run(stop);  // returns by itself at the end of the capture
  EXPECT_TRUE(loop.counters().end_of_stream.load());
  EXPECT_EQ(loop.counters().samples_pushed.load(), 5u);
  Sample sample;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(ring.try_pop(sample));
    EXPECT_DOUBLE_EQ(sample.t, 0.002 * i) << "source time is the capture's t";
  }
}

// A driver whose every 20th read takes 7 ms (3 periods of 2 ms and more): the loop misses cycles.
// A stream (loses nothing when read late, as a replayed capture) or a live signal.
class SlowDriver final : public io::Driver {
 public:
  explicit SlowDriver(bool live) : live_(live) {}
  const std::string& name() const override { return name_; }
  std::span<const std::string> channels() const override { return channels_; }
  void start() override {}
  void stop() override {}
  io::ReadStatus read(const io::Tick&, std::span<double> values) noexcept override {
    ++reads_;
    if (reads_ % 20 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(7));
    values[0] = static_cast<double>(reads_);
    return io::ReadStatus::ok;
  }
  bool loses_missed_cycles() const override { return live_; }

 private:
  bool live_;
  std::uint64_t reads_ = 0;
  std::string name_ = "slow";
  std::vector<std::string> channels_ = {"v"};
};

// Reads run late by the driver above, 200 samples; the ticks of the samples.
std::vector<std::uint64_t> ticks_of_a_late_loop(bool live, std::uint64_t& missed) {
  SlowDriver driver(live);
  SpscRing<Sample> ring(512);
  AcquisitionLoop loop(2'000'000, {&driver}, ring);
  std::atomic<bool> stop{false};
  std::thread acquisition([&] { loop.run(stop); });
  while (loop.counters().samples_pushed.load() < 200) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  stop = true;
  acquisition.join();
  missed = loop.counters().missed_cycles.load();
  std::vector<std::uint64_t> ticks;
  Sample sample;
  while (ring.try_pop(sample)) ticks.push_back(sample.tick);
  return ticks;
}

// A missed cycle is a gap downstream (the worker marks skipped ticks as missing samples) only
// where a driver lost the cycle's sample. A stream read late (a replayed capture) lost nothing:
// its ticks stay consecutive however late the loop runs, and the cycles are still counted.
TEST(RealtimeLoop, MissedCyclesAreGapsOnlyWhereADriverLostTheirSamples) {
  std::uint64_t missed = 0;
  const std::vector<std::uint64_t> stream = ticks_of_a_late_loop(false, missed);
  EXPECT_GE(missed, 10u);
  ASSERT_GE(stream.size(), 200u);
  for (std::size_t i = 1; i < stream.size(); ++i) ASSERT_EQ(stream[i], stream[i - 1] + 1) << i;

  const std::vector<std::uint64_t> live = ticks_of_a_late_loop(true, missed);
  EXPECT_GE(missed, 10u);
  ASSERT_GE(live.size(), 200u);
  std::uint64_t skipped = 0;
  for (std::size_t i = 1; i < live.size(); ++i) skipped += live[i] - live[i - 1] - 1;
  EXPECT_GE(skipped, 10u);
  EXPECT_LE(skipped, missed);
}

}  // namespace
}  // namespace leakmon::realtime
