// Runs inside the qemu VM (tests/vm/run_can_vm.sh) on Debian's kernel with vcan0 up: drives the
// real SocketCAN driver while can-utils' cansend and cangen put frames on the bus, and checks
// what it decodes. Prints one `[vm] ok|FAIL ...` line per check and `VM-VERDICT pass|fail`;
// exits non-zero on any failure. Statically linked: the initramfs has no C++ runtime.
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/can/can_driver.hpp"

extern char** environ;

namespace {

// Heap allocations made by this thread, to show that read() allocates nothing on the real
// socket path (the host tests' counter lives in the gtest support library, absent here).
thread_local std::uint64_t allocations = 0;

int failures = 0;
int checks = 0;

void check(bool ok, const std::string& what) {
  ++checks;
  if (!ok) ++failures;
  std::printf("[vm] %s %s\n", ok ? "ok  " : "FAIL", what.c_str());
  std::fflush(stdout);
}

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec;
}

void sleep_ms(int ms) {
  timespec t{ms / 1000, (ms % 1000) * 1'000'000L};
  nanosleep(&t, nullptr);
}

// Runs a can-utils command to completion; returns its exit status.
int run(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct Reader {
  leakmon::io::Driver& driver;
  std::vector<double> values;
  std::uint64_t tick = 0;
  std::uint64_t allocations_in_read = 0;
  void read() {
    const std::uint64_t before = allocations;
    driver.read(leakmon::io::Tick{tick++, now_ns()}, values);
    allocations_in_read += allocations - before;
  }
};

const char* const kConfig = R"(name: vm-bus
type: can
interface: vcan0
fd: true
max_age: 5              # generous: spawning cansend under emulation takes tens of ms
max_frames_per_read: 64
receive_buffer: 65536
signals:
  - channel: p1
    id: 0x101
    length: 16
    factor: 500
    unit: Pa
  - channel: p2
    id: 0x101
    start_bit: 16
    length: 16
    factor: 500
    unit: Pa
  - channel: x
    id: 0x18FF0102
    extended: true
    start_bit: 7
    length: 32
    byte_order: motorola
    signed: true
    factor: 1.0e-6
    unit: m
  - channel: fd_tail
    id: 0x200
    start_bit: 480
    length: 16
)";

// A second socket on the same bus with a short max age, for the timestamp check.
const char* const kShortAgeConfig = R"(name: vm-bus-short
type: can
interface: vcan0
max_age: 0.2
signals:
  - channel: p1
    id: 0x101
    length: 16
    factor: 500
)";

bool near(double a, double b) { return std::fabs(a - b) <= 1e-9 * std::max(1.0, std::fabs(b)); }

std::string show(double v) { return std::isnan(v) ? "gap" : std::to_string(v); }

}  // namespace

void* operator new(std::size_t size) {
  ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

int main() {
  using leakmon::io::can::CanDriver;
  auto config = leakmon::io::can::read_can_driver_config(
      leakmon::config::ConfigNode::load_string(kConfig, "vm-bus.yaml"));
  CanDriver driver(std::move(config));
  try {
    driver.start();
    check(true, "driver started on vcan0 (PF_CAN socket, filters, SO_TIMESTAMP, SO_RXQ_OVFL)");
  } catch (const std::exception& e) {
    check(false, std::string("driver start: ") + e.what());
    std::printf("VM-VERDICT fail (%d checks, %d failed)\n", checks, failures);
    return 1;
  }
  Reader reader{driver, std::vector<double>(4), 0, 0};
  CanDriver short_age(leakmon::io::can::read_can_driver_config(
      leakmon::config::ConfigNode::load_string(kShortAgeConfig, "vm-bus-short.yaml")));
  short_age.start();
  Reader short_reader{short_age, std::vector<double>(1), 0, 0};

  // 1. Classic frames: Intel signals and a Motorola signed signal on a 29-bit id.
  run({"cansend", "vcan0", "101#E8030204"});       // p1 = 1000*500, p2 = 0x0402*500
  run({"cansend", "vcan0", "18FF0102#FFFFFC18"});  // x = -1000 um
  reader.read();
  check(reader.values[0] == 500000.0, "p1 decoded from 101#E8030204: " + show(reader.values[0]));
  check(reader.values[1] == 0x0402 * 500.0,
        "p2 decoded from the same frame: " + show(reader.values[1]));
  check(near(reader.values[2], -0.001),
        "x (motorola, signed, 29-bit id): " + show(reader.values[2]));
  check(std::isnan(reader.values[3]), "fd_tail is a gap before any FD frame");

  // 2. CAN FD: 64 bytes, the signal sits in bytes 60..61.
  std::string fd_payload;
  for (int i = 0; i < 64; ++i) {
    char byte[3];
    std::snprintf(byte, sizeof byte, "%02X", i == 60 ? 0x34 : i == 61 ? 0x12 : i);
    fd_payload += byte;
  }
  const int fd_status = run({"cansend", "vcan0", "200##1" + fd_payload});
  reader.read();
  check(fd_status == 0 && reader.values[3] == 0x1234,
        "CAN FD 64-byte frame, signal at bit 480: " + show(reader.values[3]));

  // 3. Kernel filters: unconfigured ids and remote frames never reach the socket.
  const auto frames_before = driver.counters().frames;
  run({"cangen", "vcan0", "-I", "103", "-L", "8", "-n", "200", "-g", "0"});
  run({"cansend", "vcan0", "101#R"});
  run({"cansend", "vcan0", "00000101#1122"});  // same number as p1's id, but 29-bit
  reader.read();
  check(driver.counters().frames == frames_before,
        "filters: 200 frames of 0x103, a remote 0x101 and a 29-bit 0x101 were not received "
        "(frames " +
            std::to_string(driver.counters().frames - frames_before) + ")");
  check(reader.values[0] == 500000.0, "p1 unchanged by the filtered frames");

  // 4. Kernel timestamps: a frame that waited 500 ms in the socket queue is older than the
  //    200 ms max age of the second driver, although its read() sees it only now.
  run({"cansend", "vcan0", "101#D0070000"});
  sleep_ms(500);
  short_reader.read();
  reader.read();
  check(std::isnan(short_reader.values[0]),
        "frame queued 500 ms ago is a gap at max age 200 ms (kernel receive time, not read "
        "time): " +
            show(short_reader.values[0]));
  check(short_age.health().stale_values == 1, "stale value counted in DriverHealth");
  check(reader.values[0] == 1000000.0,
        "the same frame is fresh at max age 5 s: " + show(reader.values[0]));
  run({"cansend", "vcan0", "101#B80B0000"});
  reader.read();
  check(reader.values[0] == 1500000.0, "a newer frame replaces it: " + show(reader.values[0]));

  // 5. Error frames become health, never values.
  run({"cansend", "vcan0", "20000040#0000000000000000"});  // CAN_ERR_BUSOFF
  reader.read();
  check(driver.health().detail == "bus-off" && driver.counters().bus_off == 1,
        "bus-off error frame -> state '" + driver.health().detail + "', last error '" +
            driver.health().last_error + "'");
  check(reader.values[0] == 1500000.0, "values unaffected by the error frame");
  run({"cansend", "vcan0", "20000100#0000000000000000"});  // CAN_ERR_RESTARTED
  reader.read();
  check(driver.health().detail == "ok",
        "controller restarted -> state '" + driver.health().detail + "'");
  run({"cansend", "vcan0", "20000004#0020000000000000"});  // CAN_ERR_CRTL, TX passive
  reader.read();
  check(driver.health().detail == "error-passive",
        "controller error-passive -> state '" + driver.health().detail + "'");
  run({"cansend", "vcan0", "20000004#0040000000000000"});  // CAN_ERR_CRTL_ACTIVE
  reader.read();

  // 6. Overflow: 2000 frames into a 128 KiB receive queue while nobody reads. The kernel drops
  //    what does not fit; the drop count rides on the next frame queued after the overflow
  //    (SO_RXQ_OVFL), and each read() drains at most 64 frames.
  const auto before_flood = driver.counters();
  run({"cangen", "vcan0", "-I", "101", "-L", "8", "-D", "i", "-n", "2000", "-g", "0"});
  reader.read();
  const auto after_one_read = driver.counters();
  check(after_one_read.frames - before_flood.frames == 64,
        "one read() drained max_frames_per_read = 64 frames (" +
            std::to_string(after_one_read.frames - before_flood.frames) + ")");
  for (int i = 0; i < 100; ++i) reader.read();
  run({"cansend", "vcan0", "101#00000000"});
  reader.read();
  const auto after_flood = driver.counters();
  const std::uint64_t received = after_flood.frames - before_flood.frames;
  const std::uint64_t dropped = after_flood.kernel_drops - before_flood.kernel_drops;
  check(dropped > 0 && received + dropped == 2001, "SO_RXQ_OVFL: received " +
                                                       std::to_string(received) + " + dropped " +
                                                       std::to_string(dropped) + " = 2001 sent");
  check(driver.health().errors >= dropped, "drops counted as errors in DriverHealth");
  check(std::string(driver.health().last_error).find("dropped") != std::string::npos,
        "last error: " + driver.health().last_error);

  // 7. Interface down: the socket reports it, values age into gaps, and come back after up.
  run({"ip", "link", "set", "vcan0", "down"});
  reader.read();
  check(driver.health().detail == "interface-down",
        "link down -> state '" + driver.health().detail + "'");
  sleep_ms(300);
  short_reader.read();
  check(std::isnan(short_reader.values[0]),
        "values are gaps once older than max age while the link is down");
  run({"ip", "link", "set", "vcan0", "up"});
  run({"cansend", "vcan0", "101#01000200"});
  reader.read();
  check(driver.health().detail == "ok" && reader.values[0] == 500.0,
        "link up again -> state '" + driver.health().detail + "', p1 " + show(reader.values[0]));

  // 8. The real-time path allocated nothing in all of the above.
  check(reader.allocations_in_read == 0,
        "read() allocated nothing over " + std::to_string(reader.tick) + " reads (" +
            std::to_string(reader.allocations_in_read) + " allocations)");

  driver.stop();
  short_age.stop();
  std::printf("VM-VERDICT %s (%d checks, %d failed)\n", failures == 0 ? "pass" : "fail", checks,
              failures);
  return failures == 0 ? 0 : 1;
}
