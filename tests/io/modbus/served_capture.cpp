#include "tests/io/modbus/served_capture.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "capture/capture.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::test {
namespace {

constexpr double kRate = 500.0;
// Channel order in driver_channels(), which is the order Driver::read fills values.
enum Column { kIndexH, kP1, kP2, kX, kIndexI, kU, kValve, kColumns };

}  // namespace

std::int64_t monotonic_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

ServedCapture::ServedCapture(const std::string& dir, int rows) : path_(dir + "/served.csv") {
  capture::CaptureWriter writer(path_, {"t", "p1", "p2", "x", "u", "valve"},
                                {{"sample_rate_hz", "500"}, {"source", "modbus driver test"}});
  for (int i = 0; i < rows; ++i) {
    const double t = i / kRate;
    const double p1 = 8.65e6 + 2.0e5 * std::sin(2 * M_PI * 1.3 * t) + 1.0e4 * std::sin(97.0 * t);
    const double p2 = std::round(8.6e6 + 1.5e5 * std::cos(2 * M_PI * 0.7 * t));
    const double x = std::round(3000.0 * std::sin(2 * M_PI * 0.5 * t)) * 1e-6;
    const double u = 0.5 * std::sin(2 * M_PI * 2.1 * t);
    const double valve = (i / 400) % 2;
    writer.write_row(std::vector<double>{t, p1, p2, x, u, valve});
    // What the driver must deliver: the served encodings decoded and scaled back.
    p1_.push_back(static_cast<double>(static_cast<float>(p1 / 1e5)) * 1e5);
    p2_.push_back((p2 - 1e6) * 1.0 + 1e6);
    x_.push_back(std::round(x / 1e-6) * 1e-6);
    u_.push_back(u);
    valve_.push_back(valve);
  }
  writer.close();
}

std::string ServedCapture::server_map() {
  return "index_h:holding:0:UINT32:ABCD:1:0,"
         "p1:holding:2:FLOAT32:CDAB:100000:0,"
         "p2:holding:4:INT32:DCBA:1:1000000,"
         "x:holding:6:INT16:BADC:0.000001:0,"
         "index_i:input:10:UINT32:CDAB:1:0,"
         "u:input:12:FLOAT64:ABCD:1:0,"
         "valve:coil:5:UINT16:ABCD:1:0";
}

std::string ServedCapture::driver_channels() {
  return "address_base: 1\n"
         "channels:\n"
         "  - {name: index_h, register: holding, address: 1, data_type: UINT32}\n"
         "  - {name: p1, register: holding, address: 3, data_type: FLOAT32, byte_order: CDAB,"
         " scale: 1.0e5}\n"
         "  - {name: p2, register: holding, address: 5, data_type: INT32, byte_order: DCBA,"
         " offset: 1.0e6}\n"
         "  - {name: x, register: holding, address: 7, data_type: INT16, byte_order: BADC,"
         " scale: 1.0e-6}\n"
         "  - {name: index_i, register: input, address: 11, data_type: UINT32,"
         " byte_order: CDAB}\n"
         "  - {name: u, register: input, address: 13, data_type: FLOAT64}\n"
         "  - {name: valve, register: coil, address: 6}\n";
}

void ServedCapture::check(std::int64_t tick_ns, std::span<const double> values,
                          std::int64_t deadline_ns, Tally& tally) const {
  ++tally.ticks;
  bool all_fresh = true;
  for (double v : values) {
    if (std::isnan(v)) {
      all_fresh = false;
    } else if (tick_ns > deadline_ns) {
      ++tally.values_after_deadline;
    }
  }
  all_fresh ? ++tally.fresh : ++tally.gaps;

  const auto rows = p1_.size();
  const auto mismatch = [&](double got, double want) {
    if (!std::isnan(got) && got != want) {
      if (tally.mismatches == 0)
        tally.first_mismatch = "got " + std::to_string(got) + ", served " + std::to_string(want) +
                               " (index_h " + std::to_string(values[kIndexH]) + ", index_i " +
                               std::to_string(values[kIndexI]) + ")";
      ++tally.mismatches;
    }
  };
  // One request carries index_h, p1, p2 and x: they are from the same capture row.
  if (!std::isnan(values[kIndexH])) {
    const auto row = static_cast<std::size_t>(values[kIndexH]) % rows;
    mismatch(values[kP1], p1_[row]);
    mismatch(values[kP2], p2_[row]);
    mismatch(values[kX], x_[row]);
    // The coil is a separate request, answered up to max_age_ms (at most 100 ms, 50 samples, in
    // these tests) from the registers, plus the requests' own latency (tens of ms under TSan
    // right after a reconnect): it must match a row within 150 samples (it flips every 400, so
    // a coil stuck at the wrong state or read as 0 while 1 is served is still caught).
    if (!std::isnan(values[kValve])) {
      bool near = false;
      for (std::size_t d = 0; d < 301; ++d)
        near |= valve_[(row + rows + d - 150) % rows] == values[kValve];
      if (!near) {
        if (tally.mismatches == 0) tally.first_mismatch = "valve far from its row";
        ++tally.mismatches;
      }
    }
  } else if (!std::isnan(values[kP1]) || !std::isnan(values[kP2]) || !std::isnan(values[kX])) {
    if (tally.mismatches == 0) tally.first_mismatch = "holding values without their index";
    ++tally.mismatches;  // values of one request are fresh or stale together
  }
  if (!std::isnan(values[kIndexI])) {
    const auto row = static_cast<std::size_t>(values[kIndexI]) % rows;
    mismatch(values[kU], u_[row]);
  } else if (!std::isnan(values[kU])) {
    if (tally.mismatches == 0) tally.first_mismatch = "input values without their index";
    ++tally.mismatches;
  }
}

ServedCapture::Tally ServedCapture::run(io::Driver& driver, double seconds,
                                        std::int64_t deadline_ns) const {
  Tally tally;
  std::vector<double> values(driver.channels().size());
  EXPECT_EQ(values.size(), static_cast<std::size_t>(kColumns));
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / kRate));
  auto next = std::chrono::steady_clock::now();
  const auto end = next + std::chrono::nanoseconds(static_cast<std::int64_t>(seconds * 1e9));
  std::uint64_t index = 0;
  while (next < end) {
    std::this_thread::sleep_until(next);
    const io::Tick tick{index++, monotonic_ns()};
    {
      AllocationScope scope;
      driver.read(tick, values);
      tally.allocations += scope.count();
    }
    check(tick.monotonic_ns, values, deadline_ns, tally);
    next += period;
  }
  return tally;
}

bool ServedCapture::run_until_fresh(io::Driver& driver, int fresh_ticks, double limit_seconds,
                                    Tally& tally) const {
  std::vector<double> values(driver.channels().size());
  const auto end = std::chrono::steady_clock::now() +
                   std::chrono::nanoseconds(static_cast<std::int64_t>(limit_seconds * 1e9));
  int in_a_row = 0;
  std::uint64_t index = 0;
  while (std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    const io::Tick tick{index++, monotonic_ns()};
    driver.read(tick, values);
    const auto fresh_before = tally.fresh;
    check(tick.monotonic_ns, values, INT64_MAX, tally);
    in_a_row = tally.fresh > fresh_before ? in_a_row + 1 : 0;
    if (in_a_row >= fresh_ticks) return true;
  }
  return false;
}

}  // namespace leakmon::test
