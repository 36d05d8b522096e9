#include "daemon/driver_registry.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

#include "io/replay/replay_driver.hpp"
#ifdef LEAKMON_HAVE_SIM
#include "io/sim/sim_driver.hpp"
#endif
#ifdef LEAKMON_HAVE_MODBUS
#include "io/modbus/modbus_driver.hpp"
#endif
#ifdef LEAKMON_HAVE_CAN
#include "io/can/can_driver.hpp"
#endif
#ifdef LEAKMON_HAVE_CANLOG
#include "io/canlog/canlog_driver.hpp"
#endif

namespace leakmon::daemon {
namespace {

constexpr DriverType kDriverTypes[] = {
#ifdef LEAKMON_HAVE_SIM
    {"sim", io::make_sim_driver},
#endif
    {"replay", io::make_replay_driver},
#ifdef LEAKMON_HAVE_MODBUS
    {"modbus", io::make_modbus_driver},
#endif
#ifdef LEAKMON_HAVE_CAN
    {"can", io::make_can_driver},
#endif
#ifdef LEAKMON_HAVE_CANLOG
    {"canlog", io::make_canlog_driver},
#endif
};

}  // namespace

std::span<const DriverType> driver_types() { return kDriverTypes; }

std::unique_ptr<io::Driver> make_driver(const config::ConfigNode& node) {
  const auto type_node = node.at("type");
  const std::string type = type_node.as_string();
  for (const auto& entry : kDriverTypes) {
    if (entry.type == type) return entry.factory(node);
  }
  std::vector<std::string_view> known;
  for (const auto& entry : kDriverTypes) known.push_back(entry.type);
  type_node.fail(fmt::format("unknown driver type '{}' (known: {})", type, fmt::join(known, ", ")));
}

}  // namespace leakmon::daemon
