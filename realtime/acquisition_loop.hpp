// One sampling group's acquisition loop: every period, read each driver's channels into one
// Sample and push it into the group's ring buffer. On its own thread it runs at a fixed phase
// (clock_nanosleep to an absolute `next`, then `next += period`); a late wake-up that skips
// whole periods counts an overrun and the missed cycles and keeps the phase. A full ring drops
// the sample and counts it: the loop never waits for the worker. After start-up the loop
// allocates nothing, takes no lock, does no I/O and logs nothing; it only updates atomics that
// other threads read (LoopCounters).
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "io/driver.hpp"
#include "realtime/latency_histogram.hpp"
#include "realtime/sample.hpp"
#include "realtime/spsc_ring.hpp"

namespace leakmon::realtime {

struct LoopCounters {
  std::atomic<std::uint64_t> cycles{0};  // cycles run (ticks minus missed)
  std::atomic<std::uint64_t> samples_pushed{0};
  std::atomic<std::uint64_t> ring_drops{0};  // samples lost because the ring was full
  std::atomic<std::uint64_t> ring_high_water{0};
  std::atomic<std::uint64_t> overruns{0};       // late wake-ups that skipped a period
  std::atomic<std::uint64_t> missed_cycles{0};  // periods skipped by those overruns
  std::atomic<std::int64_t> last_cycle_ns{0};   // CLOCK_MONOTONIC of the newest cycle (watchdog)
  std::atomic<bool> running{false};
  std::atomic<bool> end_of_stream{false};  // a finite driver (replay) ran out
  LatencyHistogram wakeup_latency;         // actual minus scheduled wake-up
};

// What the real-time setup achieved; the messages are logged once, at start-up.
struct RealtimeReport {
  bool fifo = false;
  bool affinity = false;
  std::vector<std::string> warnings;
};

// Applies SCHED_FIFO at `priority` (0: leave the policy) and CPU affinity to the calling thread
// and prefaults its stack. Missing privileges become warnings, never failures.
RealtimeReport make_thread_realtime(int priority, const std::vector<int>& cpus);

// Locks current and future memory (mlockall); a warning string when not permitted, else empty.
std::string lock_process_memory();

std::int64_t monotonic_now_ns() noexcept;

class AcquisitionLoop {
 public:
  // `drivers` must outlive the loop; their channels are laid out in this order in Sample.
  AcquisitionLoop(std::int64_t period_ns, std::vector<io::Driver*> drivers, SpscRing<Sample>& ring);

  std::int64_t period_ns() const { return period_ns_; }
  std::size_t channel_count() const { return channel_count_; }
  LoopCounters& counters() { return counters_; }
  const LoopCounters& counters() const { return counters_; }

  // One cycle for `tick` at time `now_ns`: read every driver, push one Sample. Returns false
  // when a finite driver has ended (nothing pushed).
  bool cycle(const io::Tick& tick, std::int64_t now_ns) noexcept;

  // Like cycle(), for a simulated clock that may wait for the consumer: false also when the
  // ring is full, in which case nothing was read (call again after draining).
  bool cycle_if_room(const io::Tick& tick, std::int64_t now_ns) noexcept;

  // The thread body: paced cycles on CLOCK_MONOTONIC until `stop` or end of stream.
  void run(const std::atomic<bool>& stop) noexcept;

 private:
  bool read_drivers(const io::Tick& tick, std::int64_t now_ns) noexcept;
  void push() noexcept;

  std::int64_t period_ns_;
  std::vector<io::Driver*> drivers_;
  SpscRing<Sample>& ring_;
  std::size_t channel_count_ = 0;
  // Whether a missed cycle is a gap in the samples (a driver of the group loses it) or only a
  // delay (every driver a stream): Sample::tick skips the missed cycles only in the first case,
  // and the worker marks skipped ticks as gaps.
  bool missed_cycles_lose_samples_ = false;
  Sample sample_;  // built in place each cycle
  LoopCounters counters_;
};

}  // namespace leakmon::realtime
