// The acquisition loop at a given period for a given time, with `channels` simulated channels
// (the sim driver, i.e. the rig model stepped in real time) and the worker draining the ring,
// as in the daemon. Prints wake-up latency min/avg/p99/max, overruns, missed cycles, ring drops
// and the sample-to-decision latency (the path alarm events take), one `key value` per line.
// Like the daemon it holds the CPU wake-up latency request (CPU_WAKEUP_US, default 0 as in
// the daemon's config; -1 = none, to see what idle-state exits cost).
//   leakmon_loop_latency SECONDS [PERIOD_US] [PRIORITY] [ACTUATORS] [CPU_WAKEUP_US]
#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <thread>

#include "config/yaml_reader.hpp"
#include "daemon/config.hpp"
#include "io/sim/sim_driver.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/worker.hpp"
#include "realtime/acquisition_loop.hpp"
#include "realtime/cpu_latency_request.hpp"

using namespace leakmon;

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 60.0;
  const std::int64_t period_ns = (argc > 2 ? std::atoll(argv[2]) : 2000) * 1000;
  const int priority = argc > 3 ? std::atoi(argv[3]) : 80;
  const int actuators = argc > 4 ? std::atoi(argv[4]) : 1;
  const int cpu_wakeup_us = argc > 5 ? std::atoi(argv[5]) : 0;

  std::string yaml = "drivers:\n";
  for (int i = 0; i < actuators; ++i) {
    yaml += fmt::format(
        "  - {{name: rig{}, type: sim, scenario: healthy, seed: {}, "
        "channels: [xref, u, x, p1, p2]}}\n",
        i, i + 1);
  }
  yaml += "actuators:\n";
  for (int i = 0; i < actuators; ++i) {
    yaml += fmt::format(
        "  - {{name: a{0}, channels: {{p1: rig{0}.p1, p2: rig{0}.p2, u: rig{0}.u, "
        "x: rig{0}.x, xref: rig{0}.xref}}}}\n",
        i);
  }
  const auto config = daemon::parse_config(config::ConfigNode::load_string(yaml, "bench.yaml"));
  std::vector<std::unique_ptr<io::Driver>> drivers;
  std::vector<io::Driver*> raw;
  std::vector<pipeline::ChannelRef> channels;
  for (const auto& d : config.drivers) {
    drivers.push_back(io::make_sim_driver(*d.node));
    drivers.back()->start();
    raw.push_back(drivers.back().get());
    for (const auto& c : drivers.back()->channels()) channels.push_back({d.name, c, std::nullopt});
  }
  const std::string lock_warning = realtime::lock_process_memory();
  realtime::CpuLatencyRequest cpu_latency;
  if (cpu_wakeup_us >= 0) cpu_latency = realtime::CpuLatencyRequest(cpu_wakeup_us);
  realtime::SpscRing<realtime::Sample> ring(8192);
  realtime::AcquisitionLoop loop(period_ns, raw, ring);
  pipeline::CollectingEventSink events;
  pipeline::Worker worker(config, {pipeline::GroupInput{"main", &ring, channels, period_ns}},
                          {&events});

  std::atomic<bool> stop{false};
  realtime::RealtimeReport report;
  std::thread acquisition([&] {
    report = realtime::make_thread_realtime(priority, {});
    loop.run(stop);
  });
  std::atomic<bool> stop_worker{false};
  std::thread consumer([&] {
    realtime::make_thread_realtime(config.worker_priority, {});
    while (!stop_worker.load()) {
      if (worker.drain(realtime::monotonic_now_ns()) == 0) {
        std::this_thread::sleep_for(std::chrono::nanoseconds(config.worker_poll_ns));
      }
    }
  });
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  stop.store(true);
  acquisition.join();
  stop_worker.store(true);
  consumer.join();

  const auto& c = loop.counters();
  const auto& w = c.wakeup_latency;
  const auto& d = worker.decision_latency();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  fmt::print(
      "channels {}\nperiod_us {}\nsched_fifo {}\nmlockall {}\ncpu_wakeup_request {}\ncycles {}\n",
      loop.channel_count(), period_ns / 1000, report.fifo ? 1 : 0, lock_warning.empty() ? 1 : 0,
      cpu_latency.held() ? cpu_wakeup_us : -1, c.cycles.load());
  fmt::print(
      "wakeup_min_us {:.1f}\nwakeup_avg_us {:.1f}\nwakeup_p99_us {:.1f}\nwakeup_max_us {:.1f}\n",
      static_cast<double>(w.min_ns()) / 1e3, w.mean_ns() / 1e3,
      static_cast<double>(w.quantile_ns(0.99)) / 1e3, static_cast<double>(w.max_ns()) / 1e3);
  fmt::print("overruns {}\nmissed_cycles {}\nring_drops {}\nring_high_water {}\n",
             c.overruns.load(), c.missed_cycles.load(), c.ring_drops.load(),
             c.ring_high_water.load());
  fmt::print("decision_p50_us {:.1f}\ndecision_p99_us {:.1f}\ndecision_max_us {:.1f}\n",
             static_cast<double>(d.quantile_ns(0.5)) / 1e3,
             static_cast<double>(d.quantile_ns(0.99)) / 1e3, static_cast<double>(d.max_ns()) / 1e3);
  fmt::print("max_rss_kb {}\n", usage.ru_maxrss);
  return 0;
}
