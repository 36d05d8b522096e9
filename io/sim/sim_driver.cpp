#include "io/sim/sim_driver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "capture/units.hpp"

namespace leakmon::io {
namespace {

double field(const sim::RigSample& s, std::size_t index) {
  switch (index) {
    case 0:
      return s.xref;
    case 1:
      return s.u;
    case 2:
      return s.x;
    case 3:
      return s.p1;
    case 4:
      return s.p2;
    case 5:
      return s.q_int;
    case 6:
      return s.ps;
    default:
      return s.temp;
  }
}

}  // namespace

SimDriver::SimDriver(SimSettings settings) : settings_(std::move(settings)) {
  std::vector<std::string> all(kSimChannels.begin(), kSimChannels.end());
  all.insert(all.end(), kSimOptionalChannels.begin(), kSimOptionalChannels.end());
  std::vector<std::string> wanted = settings_.channels;
  if (wanted.empty()) {
    wanted.assign(kSimChannels.begin(), kSimChannels.end());
    if (settings_.scenario.record.ps) wanted.emplace_back("ps");
    if (settings_.scenario.record.temp) wanted.emplace_back("temp");
  }
  for (const auto& name : wanted) {
    const auto it = std::find(all.begin(), all.end(), name);
    if (it == all.end()) {
      throw DriverError(fmt::format("sim driver '{}': no channel '{}' (it has: {})", settings_.name,
                                    name, fmt::join(all, ", ")));
    }
    channels_.push_back(name);
    fields_.push_back(static_cast<std::size_t>(it - all.begin()));
  }
}

void SimDriver::start() {
  rig_ = std::make_unique<sim::Rig>(settings_.scenario);
  if (settings_.leak)
    rig_->set_internal_leak(settings_.leak->C_L, settings_.leak->onset_s, settings_.leak->ramp_s);
  source_time_.reset();
  rig_tick_ = 0;
}

ReadStatus SimDriver::read(const Tick& tick, std::span<double> values) noexcept {
  for (std::uint64_t caught_up = 0; rig_tick_ < tick.index && caught_up < kSimMaxCatchUpSteps;
       ++caught_up, ++rig_tick_) {
    rig_->step();
  }
  const sim::RigSample sample = rig_->step();
  ++rig_tick_;
  for (std::size_t i = 0; i < fields_.size() && i < values.size(); ++i) {
    values[i] = field(sample, fields_[i]);
  }
  source_time_ = sample.t;
  return ReadStatus::ok;
}

std::unique_ptr<Driver> make_sim_driver(const config::ConfigNode& node) {
  node.expect_keys({"name", "type", "scenario", "seed", "leak", "channels"});
  SimSettings settings;
  settings.name = node.get_string("name");
  const auto scenario_node = node.at("scenario");
  const std::string scenario = scenario_node.as_string();
  const auto seed = static_cast<std::uint64_t>(node.get_int("seed", 1, 0, 1LL << 62));
  const bool is_file = scenario.ends_with(".yaml") || scenario.ends_with(".yml");
  if (is_file) {
    std::filesystem::path path(scenario);
    if (path.is_relative()) path = std::filesystem::path(node.source()).parent_path() / path;
    try {
      settings.scenario = sim::load_scenario(path.lexically_normal().string());
    } catch (const config::ConfigError&) {
      throw;  // already names the scenario file, line and column
    } catch (const std::exception& e) {
      scenario_node.fail(e.what());
    }
    if (node.has("seed")) settings.scenario.seed = seed;
  } else {
    try {
      settings.scenario = sim::preset(scenario, seed);
    } catch (const std::invalid_argument& e) {
      scenario_node.fail(e.what());
    }
  }
  if (auto leak = node.find("leak")) {
    leak->expect_keys({"C_L", "lpm_per_mpa", "onset_s", "ramp_s"});
    SimLeak injected;
    if (leak->has("C_L") == leak->has("lpm_per_mpa")) {
      leak->fail("give the leak size as exactly one of C_L [m^3/(s Pa)] or lpm_per_mpa");
    }
    injected.C_L =
        leak->has("C_L")
            ? leak->get_double("C_L", 0.0, 1e-9)
            : units::cubic_metres_per_second_pascal(leak->get_double("lpm_per_mpa", 0.0, 100.0));
    injected.onset_s = leak->get_double("onset_s", 0.0, 0.0, 1e7);
    injected.ramp_s = leak->get_double("ramp_s", 0.0, 0.0, 1e4);
    settings.leak = injected;
  }
  if (auto channels = node.find("channels")) {
    for (const auto& item : channels->items()) settings.channels.push_back(item.as_string());
  }
  try {
    return std::make_unique<SimDriver>(std::move(settings));
  } catch (const DriverError& e) {
    node.at("channels").fail(e.what());
  }
}

}  // namespace leakmon::io
