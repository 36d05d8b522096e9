#include "daemon/config.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <net/if.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "capture/units.hpp"
#include "daemon/driver_registry.hpp"
#include "daemon/output_registry.hpp"
#include "detect/factory.hpp"
#include "detect/rig_options.hpp"
#include "io/modbus/modbus_config.hpp"
#include "io/modbus/modbus_link.hpp"
#include "realtime/sample.hpp"
#include "sim/rig_draw.hpp"

namespace leakmon::daemon {
namespace {

using capture::Role;

std::string checked_name(const config::ConfigNode& node, std::set<std::string>& seen,
                         std::string_view what) {
  const auto name_node = node.at("name");
  const std::string name = name_node.as_string();
  if (config::printable(name, name.size() + 1) != name) {
    name_node.fail(
        fmt::format("{} name '{}' must be printable text (no control characters, "
                    "valid UTF-8)",
                    what, name));
  }
  if (name.empty() || name.find_first_of(". \t/") != std::string::npos) {
    name_node.fail(
        fmt::format("{} name '{}' must be non-empty, without '.', '/' or spaces", what, name));
  }
  if (!seen.insert(name).second) name_node.fail(fmt::format("duplicate {} name '{}'", what, name));
  return name;
}

pipeline::ChannelRef parse_channel_ref(const config::ConfigNode& node, const DaemonConfig& config) {
  const std::string text = node.as_string();
  const auto dot = text.find('.');
  pipeline::ChannelRef ref;
  ref.where = node;
  if (dot == std::string::npos) {
    if (config.drivers.size() != 1) {
      node.fail(
          fmt::format("'{}': name the driver as 'driver.channel' when there are several "
                      "drivers",
                      text));
    }
    ref.driver = config.drivers.front().name;
    ref.channel = text;
  } else {
    ref.driver = text.substr(0, dot);
    ref.channel = text.substr(dot + 1);
  }
  if (ref.channel.empty()) node.fail(fmt::format("'{}': empty channel name", text));
  const bool known =
      std::any_of(config.drivers.begin(), config.drivers.end(),
                  [&](const pipeline::DriverConfig& d) { return d.name == ref.driver; });
  if (!known) node.fail(fmt::format("'{}': no driver named '{}'", text, ref.driver));
  return ref;
}

dsp::FeatureParams parse_features(const config::ConfigNode& node) {
  node.expect_keys({"wavelet", "level", "window", "step", "mode"});
  dsp::FeatureParams params;
  params.wavelet = node.get_string("wavelet", params.wavelet);
  params.level = static_cast<int>(node.get_int("level", params.level, 1, 12));
  params.window = static_cast<std::size_t>(
      node.get_int("window", static_cast<long long>(params.window), 2, 1 << 20));
  params.step = static_cast<std::size_t>(
      node.get_int("step", static_cast<long long>(params.step), 1, 1 << 20));
  if (auto mode = node.find("mode")) {
    try {
      params.mode = dsp::parse_mode(mode->as_string());
    } catch (const std::invalid_argument& e) {
      mode->fail(e.what());
    }
  }
  try {
    dsp::validate(params);
  } catch (const std::invalid_argument& e) {
    node.fail(e.what());
  }
  return params;
}

// Leak sizes as a rig engineer reads them: `min_leak: 0.03 l/min/MPa` (the detectors' options
// are in m^3/(s Pa)). The value is rewritten in place as its SI number, so the detector reads it
// as before and its range errors still point at the field.
void convert_leak_sizes(const config::ConfigNode& options) {
  if (!options.is_map()) return;
  constexpr std::string_view kUnit = "l/min/MPa";
  for (const auto& [key, value] : options.entries()) {
    if (!value.is_scalar()) continue;
    const std::string text = value.as_string();
    const auto unit = text.find(kUnit);
    if (unit == std::string::npos) continue;
    if (key != "design_leak" && key != "min_leak") {
      value.fail(
          fmt::format("{} is not a leak size (l/min/MPa applies to design_leak and "
                      "min_leak)",
                      key));
    }
    std::string number = text.substr(0, unit);
    while (!number.empty() && number.back() == ' ') number.pop_back();
    const bool unit_last = text.find_first_not_of(' ', unit + kUnit.size()) == std::string::npos;
    double lpm_per_mpa = 0.0;
    const auto [end, error] =
        std::from_chars(number.data(), number.data() + number.size(), lpm_per_mpa);
    if (number.empty() || error != std::errc() || end != number.data() + number.size() ||
        !unit_last || !std::isfinite(lpm_per_mpa)) {
      value.fail(
          fmt::format("expected a number followed by l/min/MPa (e.g. 0.03 l/min/MPa), got "
                      "'{}'",
                      text));
    }
    YAML::Node scalar = value.yaml();  // shares the document's node: the detector sees SI
    scalar = fmt::format("{:.17g}", units::cubic_metres_per_second_pascal(lpm_per_mpa));
  }
}

pipeline::AlarmSettings parse_alarm(const config::ConfigNode& node) {
  node.expect_keys({"name", "raise", "clear", "on_delay_s", "off_delay_s", "latching",
                    "not_judged_event_seconds"});
  pipeline::AlarmSettings alarm{NAN, NAN, 0.0, 0.0, false};
  if (node.has("raise")) alarm.raise_threshold = node.get_double("raise", -1e9, 1e9);
  if (node.has("clear")) alarm.clear_threshold = node.get_double("clear", -1e9, 1e9);
  if (!std::isnan(alarm.raise_threshold) && !std::isnan(alarm.clear_threshold) &&
      alarm.clear_threshold >= alarm.raise_threshold) {
    node.at("clear").fail(
        fmt::format("clear threshold {} must be below the raise threshold {} "
                    "(the deadband)",
                    alarm.clear_threshold, alarm.raise_threshold));
  }
  alarm.on_delay_s = node.get_double("on_delay_s", 0.0, 0.0, 86400.0);
  alarm.off_delay_s = node.get_double("off_delay_s", 0.0, 0.0, 86400.0);
  alarm.latching = node.get_bool("latching", false);
  alarm.not_judged_event_seconds =
      node.get_double("not_judged_event_seconds", alarm.not_judged_event_seconds, 0.0, 1e7);
  return alarm;
}

// One `transducers:` entry; what is left out keeps `spec`'s value. `bits` sets the resolution
// to the range over 2^bits (only for a finite range); `resolution` sets it directly.
detect::TransducerSpec parse_transducer(const config::ConfigNode& node,
                                        detect::TransducerSpec spec) {
  node.expect_keys({"check", "min", "max", "bits", "resolution", "noise_sigma"});
  spec.enabled = node.get_bool("check", spec.enabled);
  spec.min = node.get_double("min", spec.min, -1e12, 1e12);
  spec.max = node.get_double("max", spec.max, -1e12, 1e12);
  if (!(spec.max > spec.min)) {
    node.fail(fmt::format("max {} must be above min {}", spec.max, spec.min));
  }
  if (node.has("bits") && node.has("resolution")) {
    node.at("resolution").fail("give either bits or resolution, not both");
  }
  if (node.has("bits")) {
    if (!std::isfinite(spec.min) || !std::isfinite(spec.max)) {
      node.at("bits").fail("bits needs a finite range: give min and max (or resolution)");
    }
    const auto bits = node.get_int("bits", 1, 32);
    spec.resolution = (spec.max - spec.min) / std::ldexp(1.0, static_cast<int>(bits));
  } else if (node.has("resolution")) {
    spec.resolution = node.get_double("resolution", 0.0, 1e12);
  } else if (node.has("min") || node.has("max")) {
    // A new range keeps the default's bit count (12) rather than its LSB in pascals.
    if (std::isfinite(spec.min) && std::isfinite(spec.max)) {
      spec.resolution = (spec.max - spec.min) / 4096.0;
    }
  }
  spec.noise_sigma = node.get_double("noise_sigma", spec.noise_sigma, 0.0, 1e12);
  return spec;
}

// A detector option that restates a value of the actuator's `rig:` overrides it: valid, but the
// two places may disagree, so say where both are.
void warn_restated(const pipeline::ActuatorConfig& actuator, const config::ConfigNode& rig_node,
                   std::vector<std::string>& warnings) {
  if (!actuator.detector_options) return;
  for (const auto& restated :
       detect::restated_rig_values(*actuator.detector_options, actuator.rig)) {
    std::string places;
    for (const auto& key : restated.rig_keys) {
      if (!places.empty()) places += ", ";
      places += fmt::format("{} at {}", key, rig_node.at(key).location());
    }
    warnings.push_back(fmt::format(
        "{}: {}: actuator '{}': also given in its rig: ({}); the detector uses this option. Give "
        "the value once, in rig:",
        restated.option.location(), restated.option.path(), actuator.name, places));
  }
}

pipeline::ActuatorConfig parse_actuator(const config::ConfigNode& node, const DaemonConfig& config,
                                        std::set<std::string>& names,
                                        std::vector<std::string>& warnings) {
  node.expect_keys({"name", "channels", "features", "detector", "alarm", "transducers", "rig"});
  pipeline::ActuatorConfig actuator;
  actuator.name = checked_name(node, names, "actuator");
  const auto channels = node.at("channels");
  std::vector<std::string> role_names;
  for (const Role role : capture::kRoles) role_names.emplace_back(capture::to_string(role));
  channels.expect_keys(role_names);
  const pipeline::ChannelRef& p1 = actuator.channels[Role::p1];
  actuator.channels[Role::p1] = parse_channel_ref(channels.at("p1"), config);
  for (const Role role : capture::kRoles) {
    if (role == Role::p1) continue;
    if (auto n = channels.find(capture::to_string(role))) {
      actuator.channels[role] = parse_channel_ref(*n, config);
    }
  }
  // One actuator's signals must be sampled together (one group, one clock).
  const pipeline::GroupConfig* group = pipeline::group_of_driver(config, p1.driver);
  for (const Role role : capture::kRoles) {
    const pipeline::ChannelRef& ref = actuator.channels[role];
    if (ref.present() && pipeline::group_of_driver(config, ref.driver) != group) {
      channels.fail(
          fmt::format("channel '{}' is sampled in another group than p1 '{}': one "
                      "actuator's channels must come from one sampling group",
                      ref.text(), p1.text()));
    }
  }
  if (auto features = node.find("features")) actuator.features = parse_features(*features);
  if (auto detector = node.find("detector")) {
    if (detector->is_scalar()) {
      actuator.detector = detector->as_string();
    } else {
      detector->expect_keys({"kind", "options"});
      actuator.detector = detector->get_string("kind", "default");
      actuator.detector_options = detector->find("options");
      if (actuator.detector_options) convert_leak_sizes(*actuator.detector_options);
    }
    const auto kinds = detect::detector_kinds();
    if (std::find(kinds.begin(), kinds.end(), actuator.detector) == kinds.end()) {
      detector->fail(fmt::format("unknown detector '{}' (known: {})", actuator.detector,
                                 fmt::join(kinds, ", ")));
    }
  }
  const auto rig = node.find("rig");
  if (rig) {
    pipeline::apply_rig(actuator, sim::read_rig(*rig));
    warn_restated(actuator, *rig, warnings);
  }
  if (auto alarm = node.find("alarm")) {
    actuator.alarm = parse_alarm(*alarm);
    actuator.alarm_name = alarm->get_string("name", actuator.alarm_name);
  }
  if (auto transducers = node.find("transducers")) {
    std::vector<std::string> checked;
    for (const Role role : pipeline::kCheckedRoles) checked.emplace_back(capture::to_string(role));
    transducers->expect_keys(checked);
    for (const Role role : pipeline::kCheckedRoles) {
      if (auto n = transducers->find(capture::to_string(role))) {
        actuator.transducers[role] = parse_transducer(*n, actuator.transducers[role]);
      }
    }
  }
  return actuator;
}

pipeline::GroupConfig parse_group(const config::ConfigNode& node, const DaemonConfig& config,
                                  std::set<std::string>& names, std::set<std::string>& grouped) {
  node.expect_keys({"name", "period_ms", "drivers", "priority", "cpus", "ring_capacity"});
  pipeline::GroupConfig group;
  group.name = checked_name(node, names, "sampling group");
  group.period_ns = static_cast<std::int64_t>(
      std::llround(node.get_double("period_ms", 2.0, 0.05, 10000.0) * 1e6));
  group.priority = static_cast<int>(node.get_int("priority", group.priority, 0, 99));
  group.ring_capacity = static_cast<std::size_t>(
      node.get_int("ring_capacity", static_cast<long long>(group.ring_capacity), 16, 1 << 22));
  if (auto cpus = node.find("cpus")) {
    for (const auto& cpu : cpus->items()) {
      group.cpus.push_back(
          static_cast<int>(cpu.check_range(static_cast<double>(cpu.as_int()), 0, 1023)));
    }
  }
  for (const auto& item : node.at("drivers").items()) {
    const std::string name = item.as_string();
    const bool known = std::any_of(config.drivers.begin(), config.drivers.end(),
                                   [&](const pipeline::DriverConfig& d) { return d.name == name; });
    if (!known) item.fail(fmt::format("no driver named '{}'", name));
    if (!grouped.insert(name).second) {
      item.fail(fmt::format("driver '{}' is already in another sampling group", name));
    }
    group.drivers.push_back(name);
  }
  if (group.drivers.empty()) node.at("drivers").fail("a sampling group needs at least one driver");
  return group;
}

}  // namespace

using config::resolve_path;

DaemonConfig parse_config(const config::ConfigNode& root) {
  root.expect_keys({"drivers", "sampling", "actuators", "events", "recording", "state", "metrics",
                    "outputs", "worker", "realtime"});
  DaemonConfig config;
  config.source = root.source();

  std::set<std::string> driver_names;
  const auto drivers = root.at("drivers");
  for (const auto& node : drivers.items()) {
    pipeline::DriverConfig driver;
    driver.name = checked_name(node, driver_names, "driver");
    driver.type = node.get_string("type");
    driver.node = node;
    config.drivers.push_back(std::move(driver));
  }
  if (config.drivers.empty()) drivers.fail("at least one driver is needed");

  if (auto sampling = root.find("sampling")) {
    std::set<std::string> group_names, grouped;
    for (const auto& node : sampling->items()) {
      config.groups.push_back(parse_group(node, config, group_names, grouped));
    }
    for (const auto& driver : config.drivers) {
      if (!grouped.count(driver.name)) {
        sampling->fail(fmt::format("driver '{}' is in no sampling group", driver.name));
      }
    }
  } else {
    pipeline::GroupConfig group;
    for (const auto& driver : config.drivers) group.drivers.push_back(driver.name);
    config.groups.push_back(group);
  }

  std::set<std::string> actuator_names;
  const auto actuators = root.at("actuators");
  for (const auto& node : actuators.items()) {
    config.actuators.push_back(parse_actuator(node, config, actuator_names, config.warnings));
  }
  if (config.actuators.empty()) actuators.fail("at least one actuator is needed");

  if (auto events = root.find("events")) {
    events->expect_keys({"log"});
    config.event_log = resolve_path(*events, events->get_string("log", ""));
    config.event_log_where = events->find("log");
  }
  if (auto recording = root.find("recording")) {
    recording->expect_keys({"directory", "rotate_seconds", "keep_files", "flush_seconds"});
    config.recording.directory = resolve_path(*recording, recording->get_string("directory"));
    config.recording.where = recording->at("directory");
    config.recording.rotate_seconds = recording->get_double("rotate_seconds", 3600.0, 1.0, 1e7);
    config.recording.keep_files =
        static_cast<std::size_t>(recording->get_int("keep_files", 24, 0, 1000000));
    config.recording.flush_seconds = recording->get_double("flush_seconds", 1.0, 0.01, 1.0);
  }
  if (auto state = root.find("state")) {
    state->expect_keys({"directory", "save_seconds"});
    config.state.directory =
        resolve_path(*state, state->get_string("directory", config.state.directory));
    config.state.save_seconds = state->get_double("save_seconds", 60.0, 1.0, 86400.0);
    config.state.where = state->find("directory");
  }
  if (auto metrics = root.find("metrics")) {
    metrics->expect_keys({"address", "port", "ack_token", "trend_seconds", "trend_interval_s"});
    config.metrics.address = metrics->get_string("address", config.metrics.address);
    if (auto address = metrics->find("address")) {
      in_addr parsed{};
      if (::inet_pton(AF_INET, config.metrics.address.c_str(), &parsed) != 1) {
        address->fail(fmt::format(
            "'{}' is not an IPv4 address (write it as digits, e.g. 127.0.0.1 or 0.0.0.0; host "
            "names such as localhost are not resolved)",
            config.metrics.address));
      }
    }
    config.metrics.port = static_cast<int>(metrics->get_int("port", config.metrics.port, 0, 65535));
    config.metrics.ack_token = metrics->get_string("ack_token", "");
    if (auto token = metrics->find("ack_token"); token && config.metrics.ack_token.size() < 16) {
      token->fail("an acknowledgement token needs at least 16 characters");
    }
    if (config.metrics.port != 0 && config.metrics.ack_token.empty() &&
        !is_loopback_address(config.metrics.address)) {
      metrics->at("address").fail(fmt::format(
          "'{}' is reachable from other machines: set metrics.ack_token (>= 16 characters) so "
          "that only holders of the token can acknowledge alarms",
          config.metrics.address));
    }
    config.metrics.trend_interval_s = metrics->get_double("trend_interval_s", 1.0, 0.1, 3600.0);
    config.metrics.trend_seconds =
        metrics->get_double("trend_seconds", config.metrics.trend_seconds, 60.0, 7 * 86400.0);
    if (config.metrics.trend_seconds / config.metrics.trend_interval_s > 1e6) {
      metrics->at("trend_seconds")
          .fail("more than 1000000 trend points per actuator: raise trend_interval_s");
    }
    config.metrics.where = metrics->find("port");
    if (!config.metrics.where) config.metrics.where = metrics;
  }
  if (auto worker = root.find("worker")) {
    worker->expect_keys({"priority", "poll_us"});
    config.worker_priority = static_cast<int>(worker->get_int("priority", 70, 0, 99));
    config.worker_poll_ns = worker->get_int("poll_us", 500, 50, 100000) * 1000;
  }
  if (auto realtime = root.find("realtime")) {
    realtime->expect_keys({"cpu_wakeup_latency_us"});
    config.cpu_wakeup_latency_us = static_cast<int>(
        realtime->get_int("cpu_wakeup_latency_us", config.cpu_wakeup_latency_us, -1, 1'000'000));
  }
  if (auto outputs = root.find("outputs")) {
    std::set<std::string> output_names;
    for (const auto& node : outputs->items()) {
      checked_name(node, output_names, "output");
      node.get_string("type");
      config.outputs.push_back(node);
    }
  }
  return config;
}

bool is_loopback_address(const std::string& address) {
  return address.rfind("127.", 0) == 0 || address == "::1" || address == "localhost";
}

DaemonConfig load_config(const std::string& path) {
  return parse_config(config::ConfigNode::load_file(path));
}

void check_channels(const DaemonConfig& config,
                    const std::vector<std::vector<std::string>>& driver_channels) {
  auto channels_of = [&](const std::string& driver) -> const std::vector<std::string>& {
    for (std::size_t i = 0; i < config.drivers.size(); ++i) {
      if (config.drivers[i].name == driver) return driver_channels.at(i);
    }
    throw std::logic_error("unknown driver " + driver);
  };
  for (const auto& group : config.groups) {
    std::size_t count = 0;
    for (const auto& driver : group.drivers) count += channels_of(driver).size();
    if (count > realtime::kMaxGroupChannels) {
      throw config::ConfigError(fmt::format("{}: sampling group '{}' has {} channels; at most {}",
                                            config.source, group.name, count,
                                            realtime::kMaxGroupChannels));
    }
  }
  for (const auto& actuator : config.actuators) {
    for (const Role role : capture::kRoles) {
      const pipeline::ChannelRef& ref = actuator.channels[role];
      if (!ref.present()) continue;
      const auto& names = channels_of(ref.driver);
      if (std::find(names.begin(), names.end(), ref.channel) != names.end()) continue;
      const std::string message = fmt::format("driver '{}' has no channel '{}' (it has: {})",
                                              ref.driver, ref.channel, fmt::join(names, ", "));
      if (ref.where) ref.where->fail(message);
      throw config::ConfigError(fmt::format("{}: {}", config.source, message));
    }
    // Build the detector once so that its options and signal needs are checked now.
    const pipeline::GroupConfig* group =
        pipeline::group_of_driver(config, actuator.channels[Role::p1].driver);
    const detect::AvailableSignals signals = pipeline::available_signals(actuator.acquired());
    const double hop_seconds = static_cast<double>(actuator.features.step) *
                               static_cast<double>(group ? group->period_ns : 2'000'000) / 1e9;
    try {
      detect::make_detector(actuator.detector, signals, hop_seconds,
                            actuator.detector_options ? &*actuator.detector_options : nullptr,
                            &actuator.rig);
    } catch (const std::invalid_argument& e) {
      throw config::ConfigError(
          fmt::format("{}: actuator '{}': {}", config.source, actuator.name, e.what()));
    }
  }
}

namespace {

[[noreturn]] void fail_at(const std::optional<config::ConfigNode>& where,
                          const DaemonConfig& config, const std::string& message) {
  if (where) where->fail(message);
  throw config::ConfigError(fmt::format("{}: {}", config.source, config::printable(message)));
}

// The deepest ancestor of `path` that exists (the path itself when it exists).
std::filesystem::path existing_ancestor(std::filesystem::path path) {
  std::error_code ec;
  while (!path.empty() && !std::filesystem::exists(path, ec)) {
    const auto parent = path.parent_path();
    if (parent == path) break;
    path = parent;
  }
  return path.empty() ? std::filesystem::path(".") : path;
}

// A directory the daemon writes into (creating it and its parents when missing): what exists
// of it must be a directory it may write to.
void check_directory(const std::string& directory, const std::optional<config::ConfigNode>& where,
                     const DaemonConfig& config, std::string_view what) {
  std::error_code ec;
  const std::filesystem::path path(directory);
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_directory(path, ec)) {
    fail_at(where, config, fmt::format("{} '{}' exists and is not a directory", what, directory));
  }
  const auto ancestor = existing_ancestor(path);
  if (!std::filesystem::is_directory(ancestor, ec)) {
    fail_at(where, config,
            fmt::format("{} '{}' cannot be created: '{}' is not a directory", what, directory,
                        ancestor.string()));
  }
  if (::access(ancestor.c_str(), W_OK | X_OK) != 0) {
    fail_at(where, config,
            fmt::format("{} '{}': '{}' is not writable by this user ({})", what, directory,
                        ancestor.string(), std::strerror(errno)));
  }
}

// A file the daemon appends to (its directory is created when missing).
void check_writable_file(const std::string& file, const std::optional<config::ConfigNode>& where,
                         const DaemonConfig& config, std::string_view what) {
  std::error_code ec;
  const std::filesystem::path path(file);
  if (std::filesystem::is_directory(path, ec)) {
    fail_at(where, config, fmt::format("{} '{}' is a directory; name a file in it", what, file));
  }
  if (std::filesystem::exists(path, ec)) {
    if (::access(path.c_str(), W_OK) != 0) {
      fail_at(where, config,
              fmt::format("{} '{}' is not writable ({})", what, file, std::strerror(errno)));
    }
    return;
  }
  check_directory(path.parent_path().empty() ? "." : path.parent_path().string(), where, config,
                  fmt::format("the directory of {}", what));
}

}  // namespace

void check_paths(const DaemonConfig& config) {
  if (!config.event_log.empty()) {
    check_writable_file(config.event_log, config.event_log_where, config, "event log");
  }
  if (!config.recording.directory.empty()) {
    check_directory(config.recording.directory, config.recording.where, config,
                    "recording directory");
  }
  if (!config.state.directory.empty()) {
    check_directory(config.state.directory, config.state.where, config, "state directory");
  }
  for (const auto& node : config.outputs) {
    if (node.get_string("type") != "jsonl" || !node.has("path")) continue;
    const auto path = node.at("path");
    check_writable_file(path.as_string(), path, config, "output file");
  }
}

void check_port(const DaemonConfig& config) {
  if (config.metrics.port == 0) return;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(config.metrics.port));
  if (::inet_pton(AF_INET, config.metrics.address.c_str(), &addr.sin_addr) != 1) {
    fail_at(config.metrics.where, config,
            fmt::format("'{}' is not an IPv4 address", config.metrics.address));
  }
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return;  // no sockets at all: the endpoint will say so itself
  // As the endpoint binds: SO_REUSEADDR, so that a restart's TIME_WAIT is no conflict.
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  const int bound = ::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr));
  const int error = errno;
  const int listening = bound == 0 ? ::listen(fd, 1) : -1;
  const int listen_error = errno;
  ::close(fd);
  if (bound == 0 && listening == 0) return;
  const int why = bound != 0 ? error : listen_error;
  std::string reason = std::strerror(why);
  if (why == EADDRINUSE) {
    reason =
        "in use by another program (a running leakmon? to check a file for `systemctl reload` "
        "while it runs, use check-config --no-probe)";
  }
  if (why == EADDRNOTAVAIL) reason = "the address is not one of this machine's";
  if (why == EACCES) reason = "ports below 1024 need privilege";
  fail_at(config.metrics.where, config,
          fmt::format("cannot listen on {}:{}: {}", config.metrics.address, config.metrics.port,
                      reason));
}

void check_devices(const DaemonConfig& config) {
  for (const auto& driver : config.drivers) {
    if (!driver.node) continue;
    const auto& node = *driver.node;
    if (driver.type == "can" && node.has("interface")) {
      const auto interface = node.at("interface");
      const std::string name = interface.as_string();
      if (::if_nametoindex(name.c_str()) == 0) {
        interface.fail(fmt::format(
            "no network interface '{}' on this machine (ip link show; for a virtual bus: ip "
            "link add dev {} type vcan)",
            name, name));
      }
    }
    if (driver.type == "modbus" && node.has("device")) {
      const auto device = node.at("device");
      const std::string path = device.as_string();
      struct stat info {};
      if (::stat(path.c_str(), &info) != 0) {
        device.fail(fmt::format("serial port '{}': {}", path, std::strerror(errno)));
      }
      if (!S_ISCHR(info.st_mode)) {
        device.fail(fmt::format("serial port '{}' is not a character device", path));
      }
      if (::access(path.c_str(), R_OK | W_OK) != 0) {
        device.fail(
            fmt::format("serial port '{}' is not readable and writable by this user "
                        "({}; the dialout group?)",
                        path, std::strerror(errno)));
      }
    }
  }
}

namespace {

// Connects to host:port within `timeout_ms`; empty on success, else why not.
std::string tcp_connect_problem(const std::string& host, int port, int timeout_ms) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (const int rc = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &found); rc != 0) {
    return fmt::format("cannot resolve '{}': {}", host, ::gai_strerror(rc));
  }
  std::string problem = "no address";
  for (const addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd =
        ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) {
      problem = std::strerror(errno);
      continue;
    }
    int error = ::connect(fd, a->ai_addr, a->ai_addrlen) == 0 ? 0 : errno;
    if (error == EINPROGRESS) {
      pollfd waiting{fd, POLLOUT, 0};
      const int ready = ::poll(&waiting, 1, timeout_ms);
      socklen_t length = sizeof(error);
      if (ready == 1) {
        ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
      } else {
        error = ETIMEDOUT;
      }
    }
    ::close(fd);
    if (error == 0) {
      ::freeaddrinfo(found);
      return "";
    }
    problem = error == ETIMEDOUT ? fmt::format("no answer within {} ms", timeout_ms)
                                 : std::string(std::strerror(error));
  }
  ::freeaddrinfo(found);
  return problem;
}

// `check-config`'s network check of a peer written at `node` (a driver or output mapping):
// `problem` is why it does not answer, empty when it does.
void check_peer(const config::ConfigNode& node, const std::string& host, int port,
                std::string_view what, const std::string& problem) {
  if (problem.empty()) return;
  const auto where = node.find("host");
  (where ? *where : node)
      .fail(fmt::format("{} {}:{} does not answer: {} (is it on, and is this the right "
                        "address? --no-peers leaves this check out)",
                        what, host, port, problem));
}

}  // namespace

void check_peers(const DaemonConfig& config) {
  constexpr int kConnectTimeoutMs = 3000;
  // A Modbus device must answer a read (a TCP connection alone can be a gateway's, or a
  // firewall's that accepts everything); the alarm output and the broker must accept one.
  for (const auto& driver : config.drivers) {
    if (!driver.node || driver.type != "modbus") continue;
    const auto modbus = io::modbus::parse_modbus_config(*driver.node);
    if (!modbus.tcp) continue;
    check_peer(*driver.node, modbus.tcp->host, modbus.tcp->port, "Modbus device",
               io::modbus::unanswered(modbus));
  }
  for (const auto& node : config.outputs) {
    const std::string type = node.get_string("type");
    if (type == "modbus" && node.get_string("transport", "tcp") == "tcp") {
      const std::string host = node.get_string("host");
      const int port = static_cast<int>(node.get_int("port", 502, 1, 65535));
      check_peer(node, host, port, "Modbus alarm output",
                 tcp_connect_problem(host, port, kConnectTimeoutMs));
    } else if (type == "mqtt") {
      const std::string host = node.get_string("host", "127.0.0.1");
      const int port =
          static_cast<int>(node.get_int("port", node.has("tls") ? 8883 : 1883, 1, 65535));
      check_peer(node, host, port, "MQTT broker",
                 tcp_connect_problem(host, port, kConnectTimeoutMs));
    }
  }
}

DaemonConfig check_config(const std::string& path, const Preflight& preflight) {
  DaemonConfig config = load_config(path);
  check_paths(config);
  if (preflight.port) check_port(config);
  if (preflight.devices) check_devices(config);
  std::vector<std::vector<std::string>> driver_channels;
  for (const auto& driver : config.drivers) {
    auto built = make_driver(*driver.node);
    const auto names = built->channels();
    driver_channels.emplace_back(names.begin(), names.end());
  }
  check_channels(config, driver_channels);
  for (const auto& node : config.outputs) make_output(node);
  for (const auto& driver : config.drivers) {
    if (driver.type != "modbus" || !driver.node) continue;
    const auto modbus = io::modbus::parse_modbus_config(*driver.node);
    config.warnings.insert(config.warnings.end(), modbus.warnings.begin(), modbus.warnings.end());
  }
  // Last: the peers are only worth asking once everything else in the file is right.
  if (preflight.peers) check_peers(config);
  return config;
}

}  // namespace leakmon::daemon
