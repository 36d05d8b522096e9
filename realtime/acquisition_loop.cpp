#include "realtime/acquisition_loop.hpp"

#include <fmt/format.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace leakmon::realtime {
namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

timespec to_timespec(std::int64_t ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(ns / kNsPerSecond);
  ts.tv_nsec = static_cast<long>(ns % kNsPerSecond);
  return ts;
}

// Touches a stack region so that its pages are mapped (and locked, after mlockall) before the
// loop starts: a first touch inside the loop would be a page fault.
[[gnu::noinline]] void prefault_stack() {
  constexpr std::size_t kBytes = 256 * 1024;
  unsigned char stack[kBytes];
  std::memset(stack, 0, kBytes);
  // Keeps the compiler from dropping the writes to a buffer nobody reads.
  asm volatile("" : : "r"(stack) : "memory");
}

}  // namespace

std::int64_t monotonic_now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

std::string lock_process_memory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    return fmt::format(
        "mlockall failed ({}): pages may fault in the real-time loop; grant "
        "CAP_IPC_LOCK or raise LimitMEMLOCK",
        std::strerror(errno));
  }
  return {};
}

RealtimeReport make_thread_realtime(int priority, const std::vector<int>& cpus) {
  RealtimeReport report;
  if (priority > 0) {
    sched_param param{};
    param.sched_priority = priority;
    const int error = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (error == 0) {
      report.fifo = true;
    } else {
      report.warnings.push_back(
          fmt::format("SCHED_FIFO priority {} not permitted ({}): running with normal "
                      "scheduling; grant CAP_SYS_NICE or raise LimitRTPRIO",
                      priority, std::strerror(error)));
    }
  }
  if (!cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int cpu : cpus) CPU_SET(static_cast<std::size_t>(cpu), &set);
    const int error = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (error == 0) {
      report.affinity = true;
    } else {
      report.warnings.push_back(fmt::format("CPU affinity {} not applied ({})",
                                            fmt::join(cpus, ","), std::strerror(error)));
    }
  }
  prefault_stack();
  return report;
}

AcquisitionLoop::AcquisitionLoop(std::int64_t period_ns, std::vector<io::Driver*> drivers,
                                 SpscRing<Sample>& ring)
    : period_ns_(period_ns), drivers_(std::move(drivers)), ring_(ring) {
  for (const auto* driver : drivers_) {
    channel_count_ += driver->channels().size();
    missed_cycles_lose_samples_ = missed_cycles_lose_samples_ || driver->loses_missed_cycles();
  }
  if (channel_count_ > kMaxGroupChannels) {
    throw std::invalid_argument(fmt::format("a sampling group has {} channels; at most {}",
                                            channel_count_, kMaxGroupChannels));
  }
  sample_.channel_count = static_cast<std::uint32_t>(channel_count_);
}

bool AcquisitionLoop::read_drivers(const io::Tick& tick, std::int64_t now_ns) noexcept {
  sample_.tick = tick.index;
  sample_.monotonic_ns = now_ns;
  std::size_t offset = 0;
  std::optional<double> source_time;
  for (auto* driver : drivers_) {
    const std::size_t n = driver->channels().size();
    std::span<double> values(sample_.values.data() + offset, n);
    if (driver->read(tick, values) == io::ReadStatus::end_of_stream) {
      counters_.end_of_stream.store(true, std::memory_order_release);
      return false;
    }
    if (!source_time) source_time = driver->source_time();
    offset += n;
  }
  sample_.t = source_time ? *source_time
                          : static_cast<double>(tick.index) * static_cast<double>(period_ns_) / 1e9;
  return true;
}

void AcquisitionLoop::push() noexcept {
  if (ring_.try_push(sample_)) {
    counters_.samples_pushed.fetch_add(1, std::memory_order_relaxed);
    const std::uint64_t queued = ring_.size();
    if (queued > counters_.ring_high_water.load(std::memory_order_relaxed)) {
      counters_.ring_high_water.store(queued, std::memory_order_relaxed);
    }
  } else {
    counters_.ring_drops.fetch_add(1, std::memory_order_relaxed);
  }
  counters_.cycles.fetch_add(1, std::memory_order_relaxed);
}

bool AcquisitionLoop::cycle(const io::Tick& tick, std::int64_t now_ns) noexcept {
  if (!read_drivers(tick, now_ns)) return false;
  push();
  counters_.last_cycle_ns.store(now_ns, std::memory_order_relaxed);
  return true;
}

bool AcquisitionLoop::cycle_if_room(const io::Tick& tick, std::int64_t now_ns) noexcept {
  if (ring_.size() >= ring_.capacity()) return false;
  return cycle(tick, now_ns);
}

void AcquisitionLoop::run(const std::atomic<bool>& stop) noexcept {
  counters_.running.store(true, std::memory_order_release);
  io::Tick tick;
  std::int64_t next = monotonic_now_ns() + period_ns_;
  while (!stop.load(std::memory_order_acquire)) {
    const timespec deadline = to_timespec(next);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
    }
    const std::int64_t woke = monotonic_now_ns();
    counters_.wakeup_latency.record(woke - next);
    tick.monotonic_ns = next;
    if (!cycle(tick, woke)) break;

    // Keep the phase: the next wake-up is one period after this one's schedule. A cycle that
    // ends after that deadline is an overrun; the loop then starts the next cycle at once (a
    // late sample is better than a gap). Only when it is a whole period or more behind does it
    // skip those periods, counted as missed cycles, instead of bunching reads together. Their
    // ticks are skipped (gaps downstream) only where a driver lost their samples: a replayed
    // capture read late hands out its next row, and under load (a sanitizer build on a busy CI
    // machine) spurious gaps in it delayed the flow balance's learning past a test's leak.
    next += period_ns_;
    ++tick.index;
    const std::int64_t late = monotonic_now_ns() - next;
    if (late > 0) {
      counters_.overruns.fetch_add(1, std::memory_order_relaxed);
      if (late >= period_ns_) {
        const std::int64_t missed = late / period_ns_;
        counters_.missed_cycles.fetch_add(static_cast<std::uint64_t>(missed),
                                          std::memory_order_relaxed);
        next += missed * period_ns_;
        if (missed_cycles_lose_samples_) tick.index += static_cast<std::uint64_t>(missed);
      }
    }
  }
  counters_.running.store(false, std::memory_order_release);
}

}  // namespace leakmon::realtime
