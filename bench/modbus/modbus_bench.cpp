// Modbus TCP against Debian's pymodbus server on loopback (tests/io/modbus/modbus_server.py):
// read round trips per second and their latency, and the wake-up latency of a 500 Hz loop
// while the driver polls in the background (the loop the daemon runs, without SCHED_FIFO).
//
//   build/bin/modbus_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/modbus/modbus_config.hpp"
#include "io/modbus/modbus_driver.hpp"
#include "io/modbus/modbus_link.hpp"

extern char** environ;

namespace {

using namespace leakmon;

// The pymodbus server, started once for all benchmarks.
class PymodbusServer {
 public:
  PymodbusServer() {
    const std::string ready = std::filesystem::temp_directory_path() /
                              ("leakmon-modbus-bench-" + std::to_string(getpid()));
    std::filesystem::remove(ready);
    std::vector<std::string> argv = {"/usr/bin/python3",
                                     LEAKMON_SOURCE_DIR "/tests/io/modbus/modbus_server.py",
                                     "--ready-file", ready};
    std::vector<char*> args;
    for (auto& arg : argv) args.push_back(arg.data());
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], nullptr, nullptr, args.data(), environ) != 0)
      throw std::runtime_error("cannot start the pymodbus server");
    for (int i = 0; i < 1000 && !std::filesystem::exists(ready); ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    std::ifstream(ready) >> port_;
    std::filesystem::remove(ready);
    if (port_ == 0) throw std::runtime_error("the pymodbus server did not start");
  }
  ~PymodbusServer() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  int port() const { return port_; }

 private:
  pid_t pid_ = -1;
  int port_ = 0;
};

PymodbusServer& server() {
  static PymodbusServer instance;
  return instance;
}

std::string driver_yaml(int registers) {
  std::string yaml = "name: bench\nhost: 127.0.0.1\nport: " + std::to_string(server().port()) +
                     "\npoll_rate_hz: 500\ntimeout_ms: 100\nchannels:\n";
  for (int i = 0; i < registers; i += 2)
    yaml += "  - {name: c" + std::to_string(i) + ", address: " + std::to_string(i) +
            ", data_type: FLOAT32}\n";
  return yaml;
}

void add_percentiles(benchmark::State& state, std::vector<double> us, const std::string& prefix) {
  if (us.empty()) return;
  std::sort(us.begin(), us.end());
  const auto at = [&](double q) { return us[static_cast<std::size_t>(q * (us.size() - 1))]; };
  state.counters[prefix + "p50_us"] = at(0.5);
  state.counters[prefix + "p99_us"] = at(0.99);
  state.counters[prefix + "max_us"] = us.back();
}

// One read request of `registers` holding registers per iteration, as the poller sends it.
void BM_ModbusTcpRead(benchmark::State& state) {
  const int registers = static_cast<int>(state.range(0));
  const auto config = io::modbus::parse_modbus_config(
      config::ConfigNode::load_string(driver_yaml(registers), "bench.yaml"));
  io::modbus::ModbusLink link(config);
  if (link.connect() != io::modbus::Outcome::ok) {
    state.SkipWithError("cannot connect to the pymodbus server");
    return;
  }
  io::modbus::ReadRequest request{1, io::modbus::RegisterType::holding, 0, registers, {}};
  std::vector<std::uint16_t> words(125);
  std::vector<std::uint8_t> bits(1);
  std::vector<double> latency_us;
  std::size_t failures = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    if (link.read(request, words, bits) != io::modbus::Outcome::ok) ++failures;
    latency_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
            .count());
  }
  state.counters["reads_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["failures"] = static_cast<double>(failures);
  add_percentiles(state, latency_us, "");
}
BENCHMARK(BM_ModbusTcpRead)->Arg(2)->Arg(16)->Arg(124)->UseRealTime()->MinTime(2.0);

// A 500 Hz loop (absolute clock_nanosleep, next += period) reading the driver every tick;
// Arg(1): the driver polls the server meanwhile; Arg(0): the loop alone, for comparison.
void BM_LoopWakeupLatency(benchmark::State& state) {
  const bool polling = state.range(0) != 0;
  std::unique_ptr<io::Driver> driver;
  if (polling) {
    driver = io::make_modbus_driver(config::ConfigNode::load_string(driver_yaml(16), "b.yaml"));
    driver->start();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  constexpr long kPeriodNs = 2'000'000;
  constexpr int kTicks = 2500;  // 5 s
  std::vector<double> late_us;
  std::vector<double> values(8);
  std::size_t gaps = 0;
  for (auto _ : state) {
    timespec next{};
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (int tick = 0; tick < kTicks; ++tick) {
      next.tv_nsec += kPeriodNs;
      if (next.tv_nsec >= 1'000'000'000) {
        next.tv_nsec -= 1'000'000'000;
        ++next.tv_sec;
      }
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
      timespec now{};
      clock_gettime(CLOCK_MONOTONIC, &now);
      const double late_ns = static_cast<double>(now.tv_sec - next.tv_sec) * 1e9 +
                             static_cast<double>(now.tv_nsec - next.tv_nsec);
      late_us.push_back(late_ns / 1e3);
      if (driver) {
        driver->read(io::Tick{static_cast<std::uint64_t>(tick),
                              static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec},
                     values);
        gaps += std::isnan(values[0]) ? 1 : 0;
      }
    }
  }
  add_percentiles(state, late_us, "wake_");
  if (driver) {
    state.counters["gap_fraction"] =
        static_cast<double>(gaps) / static_cast<double>(late_us.size());
    driver->stop();
  }
}
BENCHMARK(BM_LoopWakeupLatency)
    ->Arg(0)
    ->Arg(1)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
