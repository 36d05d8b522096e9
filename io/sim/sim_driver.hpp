// The `sim` driver: the rig model of sim/ (MODEL.md) stepped once per tick, so the daemon can
// run against a simulated actuator in real time. The scenario is a preset or a scenario file;
// an internal leak can be injected at a given simulated time. source_time() is the rig's t.
// Like a real rig, the simulated one does not wait for the daemon: ticks the loop missed are
// stepped through (their samples lost, as a real transducer's would be), so the rig's time stays
// the tick's time and a leak set to open at 40 s opens 40 s after the start however loaded the
// machine is.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/driver.hpp"
#include "sim/rig.hpp"
#include "sim/scenario.hpp"

namespace leakmon::io {

struct SimLeak {
  double C_L = 0.0;  // m^3/(s Pa)
  double onset_s = 0.0;
  double ramp_s = 0.0;
};

struct SimSettings {
  std::string name = "sim";
  sim::Scenario scenario;
  std::optional<SimLeak> leak;        // overrides the scenario's own leak
  std::vector<std::string> channels;  // subset of kSimChannels; empty = all
};

// What the rig offers, in capture column names (FORMATS.md).
inline constexpr std::array<const char*, 6> kSimChannels = {"xref", "u", "x", "p1", "p2", "q_int"};
// Optional transducers (supply pressure, oil temperature): offered when named in `channels`,
// and part of the default set when the scenario records them (its `record:` list).
inline constexpr std::array<const char*, 2> kSimOptionalChannels = {"ps", "temp"};

class SimDriver final : public Driver {
 public:
  explicit SimDriver(SimSettings settings);

  const std::string& name() const override { return settings_.name; }
  std::span<const std::string> channels() const override { return channels_; }
  void start() override;
  void stop() override {}
  ReadStatus read(const Tick& tick, std::span<double> values) noexcept override;
  std::optional<double> source_time() const override { return source_time_; }

 private:
  SimSettings settings_;
  std::vector<std::string> channels_;
  std::vector<std::size_t> fields_;  // index into kSimChannels per channel
  std::unique_ptr<sim::Rig> rig_;
  std::optional<double> source_time_;
  std::uint64_t rig_tick_ = 0;  // the tick whose sample the rig's next step() returns
};

// Missed ticks stepped through per read at most: a stall of seconds is made up over the next
// reads instead of in one read long enough to make the next cycle late too (a step costs a few
// microseconds).
inline constexpr std::uint64_t kSimMaxCatchUpSteps = 100;

// `{name, type: sim, scenario: PRESET|FILE.yaml, seed, leak: {C_L | lpm_per_mpa, onset_s,
// ramp_s}, channels}`.
std::unique_ptr<Driver> make_sim_driver(const config::ConfigNode& node);

}  // namespace leakmon::io
