// `leakmon probe --config CONFIG.yaml [--seconds N]`: commissioning, in the manner of
// Telegraf's `--test`. Connects every configured driver, reads each channel once (the first
// value it delivers) or for N seconds, and prints it in SI units with the role an actuator gives
// it and its NAMUR NE 107 status; nothing is detected, logged or written.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "daemon/config.hpp"
#include "daemon/driver_registry.hpp"
#include "io/device_status.hpp"
#include "io/driver.hpp"

namespace leakmon::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// What the configuration's actuators make of one driver channel: its roles ("cylinder.p1"), the
// SI unit those roles are in, and the transducer range a value must lie in.
struct ChannelUse {
  std::vector<std::string> roles;
  std::string unit;  // empty: no actuator uses the channel, the unit is the driver's scaling
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
};

std::string unit_of_role(std::string_view role) {
  if (role == "p1" || role == "p2" || role == "ps") return "Pa";
  if (role == "x" || role == "xref") return "m";
  if (role == "u") return "V";
  return "degC";  // temp
}

ChannelUse use_of(const daemon::DaemonConfig& config, const std::string& driver,
                  const std::string& channel) {
  ChannelUse use;
  for (const auto& a : config.actuators) {
    for (const capture::Role role : capture::kRoles) {
      const pipeline::ChannelRef& ref = a.channels[role];
      if (!ref.present() || ref.driver != driver || ref.channel != channel) continue;
      use.roles.push_back(fmt::format("{}.{}", a.name, capture::to_string(role)));
      use.unit = unit_of_role(capture::to_string(role));
      const bool checked = std::find(pipeline::kCheckedRoles.begin(), pipeline::kCheckedRoles.end(),
                                     role) != pipeline::kCheckedRoles.end();
      const detect::TransducerSpec* spec = checked ? &a.transducers[role] : nullptr;
      if (spec != nullptr && spec->enabled) {
        use.min = std::max(use.min, spec->min);
        use.max = std::min(use.max, spec->max);
      }
    }
  }
  return use;
}

// A value in its unit, with a reading aid for pressures (MPa).
std::string format_value(double value, const std::string& unit) {
  if (std::isnan(value)) return "-";
  value += 0.0;  // -0 reads as 0
  if (unit == "Pa") return fmt::format("{:.0f} Pa ({:.3f} MPa)", value, value / 1e6);
  if (unit == "m") return fmt::format("{:.6f} m", value);
  if (unit == "V") return fmt::format("{:.4f} V", value);
  if (unit == "degC") return fmt::format("{:.2f} degC", value);
  return fmt::format("{:.6g}", value);
}

// One channel's readings over the probe.
struct Readings {
  double first = kNaN;
  double last = kNaN;
  double min = kNaN;
  double max = kNaN;
  double sum = 0.0;
  std::uint64_t values = 0;
  std::uint64_t gaps = 0;

  void add(double value) {
    if (std::isnan(value)) {
      ++gaps;
      return;
    }
    if (values == 0) first = min = max = value;
    last = value;
    min = std::min(min, value);
    max = std::max(max, value);
    sum += value;
    ++values;
  }
};

struct ProbedDriver {
  std::unique_ptr<io::Driver> driver;
  std::string type;
  std::int64_t period_ns = 2'000'000;
  std::vector<Readings> channels;
  std::vector<double> values;  // read() buffer
  io::Tick tick;
  std::int64_t next_ns = 0;
  bool ended = false;

  bool every_channel_read() const {
    return std::all_of(channels.begin(), channels.end(),
                       [](const Readings& r) { return r.values > 0; });
  }
};

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int run_probe(int argc, char** argv) {
  ArgParser args("probe",
                 "commissioning: connect every driver of a configuration, read each channel once "
                 "(or for --seconds) and print it in SI units with its NE 107 status; detects, "
                 "logs and writes nothing. Exit status 1 when a channel has no value or is not ok");
  args.option("config", "CONFIG.yaml", "daemon configuration (schema: config/README.md)",
              std::nullopt, true);
  args.option("seconds", "N",
              "read for N seconds and print each channel's last, lowest, highest and mean value "
              "(0: the first value of each channel)",
              "0");
  args.option("timeout", "SECONDS", "how long to wait for a channel's first value", "5");
  if (!args.parse(argc, argv)) return 0;
  const double seconds = args.get_double("seconds");
  const double timeout_s = args.get_double("timeout");
  if (!(seconds >= 0.0 && seconds <= 86400.0)) throw UsageError("--seconds must be in [0, 86400]");
  if (!(timeout_s > 0.0 && timeout_s <= 3600.0)) throw UsageError("--timeout must be in (0, 3600]");

  const daemon::DaemonConfig config = daemon::load_config(args.get("config"));
  std::vector<ProbedDriver> probed;
  for (const auto& driver : config.drivers) {
    ProbedDriver p;
    p.driver = daemon::make_driver(*driver.node);
    p.type = driver.type;
    if (const auto* group = pipeline::group_of_driver(config, driver.name)) {
      p.period_ns = group->period_ns;
    }
    p.channels.resize(p.driver->channels().size());
    p.values.assign(p.channels.size(), kNaN);
    probed.push_back(std::move(p));
  }
  int failures = 0;
  for (auto& p : probed) {
    try {
      p.driver->start();
    } catch (const std::exception& e) {
      fmt::print("{} ({}): cannot start: {}\n", p.driver->name(), p.type, e.what());
      p.ended = true;
      ++failures;
    }
  }

  // Every driver at its group's period, on the real clock as in the daemon. Without --seconds,
  // until each channel has delivered a value (or the timeout); with it, for that long.
  const std::int64_t start_ns = now_ns();
  const auto limit_ns = static_cast<std::int64_t>((seconds > 0.0 ? seconds : timeout_s) * 1e9);
  for (auto& p : probed) p.next_ns = start_ns;
  while (true) {
    const std::int64_t now = now_ns();
    bool waiting = false;
    std::int64_t next = now + 1'000'000'000;
    for (auto& p : probed) {
      if (p.ended) continue;
      if (seconds == 0.0 && p.every_channel_read()) continue;
      waiting = true;
      if (now >= p.next_ns) {
        p.tick.monotonic_ns = now;
        std::fill(p.values.begin(), p.values.end(), kNaN);
        if (p.driver->read(p.tick, p.values) == io::ReadStatus::end_of_stream) {
          p.ended = true;
          continue;
        }
        for (std::size_t i = 0; i < p.values.size(); ++i) {
          // Once: the first value is the reading; the gaps before it are the connection's.
          if (seconds > 0.0 || p.channels[i].values == 0) {
            if (seconds > 0.0 || !std::isnan(p.values[i])) p.channels[i].add(p.values[i]);
          }
        }
        ++p.tick.index;
        p.next_ns += p.period_ns;
        if (p.next_ns < now) p.next_ns = now + p.period_ns;  // behind: no burst of catch-up reads
      }
      next = std::min(next, p.next_ns);
    }
    if (!waiting || now - start_ns >= limit_ns) break;
    std::this_thread::sleep_for(
        std::chrono::nanoseconds(std::max<std::int64_t>(0, next - now_ns())));
  }

  std::size_t channels = 0;
  for (auto& p : probed) {
    const io::DriverHealth health = p.driver->health();
    p.driver->stop();
    fmt::print("{} ({}): {}{}{}\n", p.driver->name(), p.type, io::to_string(health.status),
               health.detail.empty() || health.detail == "ok" ? "" : " (" + health.detail + ")",
               health.last_error.empty() ? "" : ": " + health.last_error);
    const auto names = p.driver->channels();
    for (std::size_t i = 0; i < names.size(); ++i) {
      ++channels;
      const Readings& r = p.channels[i];
      const ChannelUse use = use_of(config, p.driver->name(), names[i]);
      io::DeviceStatus status = io::DeviceStatus::ok;
      std::string why;
      if (r.values == 0) {
        status = io::DeviceStatus::failure;
        why = seconds > 0.0 ? "no value" : fmt::format("no value within {:g} s", timeout_s);
      } else if (health.status != io::DeviceStatus::ok) {
        status = health.status;
        why = health.detail;
      } else if (r.min < use.min || r.max > use.max) {
        status = io::DeviceStatus::out_of_specification;
        why = fmt::format("outside the transducer's range {} .. {}",
                          format_value(use.min, use.unit), format_value(use.max, use.unit));
      }
      if (status != io::DeviceStatus::ok) ++failures;
      std::string line = fmt::format("  {}.{} = {}", p.driver->name(), names[i],
                                     format_value(seconds > 0.0 ? r.last : r.first, use.unit));
      if (seconds > 0.0) {
        line += fmt::format(
            "; min {}, max {}, mean {}; {} values, {} gaps", format_value(r.min, use.unit),
            format_value(r.max, use.unit),
            format_value(r.values > 0 ? r.sum / static_cast<double>(r.values) : kNaN, use.unit),
            r.values, r.gaps);
      }
      line += fmt::format("  [{}{}]", io::to_string(status), why.empty() ? "" : ": " + why);
      line += use.roles.empty() ? "  (no actuator uses it)"
                                : fmt::format("  {}", fmt::join(use.roles, ", "));
      fmt::print("{}\n", line);
    }
  }
  if (failures > 0) {
    fmt::print("{}: {} of {} channel(s) or driver(s) not ok\n", args.get("config"), failures,
               channels);
    return 1;
  }
  fmt::print("{}: {} channel(s) ok\n", args.get("config"), channels);
  return 0;
}

}  // namespace leakmon::cli
