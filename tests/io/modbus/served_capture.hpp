// A capture served by the pymodbus peer and the check that the driver reads it back exactly.
// The server also serves the number of the sample it is serving ("index" channels), in the same
// request as the values, so every read can be matched with the capture row it must equal.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/driver.hpp"

namespace leakmon::test {

class ServedCapture {
 public:
  // Writes the capture (dir/served.csv): p1, p2, x, u, valve over `rows` samples at 500 Hz.
  ServedCapture(const std::string& dir, int rows);

  const std::string& path() const { return path_; }
  // The server's --map for this capture.
  static std::string server_map();
  // The driver's channel list (YAML), matching server_map() with address_base 1.
  static std::string driver_channels();

  // Tallies of driver reads checked against the capture.
  struct Tally {
    std::uint64_t ticks = 0;
    std::uint64_t fresh = 0;        // ticks where every channel had a value
    std::uint64_t gaps = 0;         // ticks where some channel was a gap
    std::uint64_t mismatches = 0;   // values that differ from the served capture row: must be 0
    std::string first_mismatch;     // what the first mismatch was, for the failure message
    std::uint64_t allocations = 0;  // heap allocations inside Driver::read: must be 0
    std::uint64_t values_after_deadline = 0;  // non-gap values read after `deadline_ns`
  };

  // Runs the caller's thread as a 500 Hz acquisition loop for `seconds`, reading `driver`
  // and checking each tick. Values read after `deadline_ns` (CLOCK_MONOTONIC) are counted.
  Tally run(io::Driver& driver, double seconds, std::int64_t deadline_ns = INT64_MAX) const;
  // Runs the loop until `fresh_ticks` ticks in a row had fresh values, or `limit_seconds`.
  bool run_until_fresh(io::Driver& driver, int fresh_ticks, double limit_seconds,
                       Tally& tally) const;

 private:
  void check(std::int64_t tick_ns, std::span<const double> values, std::int64_t deadline_ns,
             Tally& tally) const;

  std::string path_;
  std::vector<double> p1_, p2_, x_, u_, valve_;
};

std::int64_t monotonic_ns();

}  // namespace leakmon::test
