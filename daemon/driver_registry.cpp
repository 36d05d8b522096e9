#include "daemon/driver_registry.hpp"

#include "io/can/can_driver.hpp"
#include "io/canlog/canlog_driver.hpp"
#include "io/modbus/modbus_driver.hpp"
#include "io/replay/replay_driver.hpp"
#include "io/sim/sim_driver.hpp"

namespace leakmon::daemon {
namespace {

constexpr DriverType kDriverTypes[] = {
    {"sim", io::make_sim_driver},       {"replay", io::make_replay_driver},
    {"modbus", io::make_modbus_driver}, {"can", io::make_can_driver},
    {"canlog", io::make_canlog_driver},
};

}  // namespace

std::span<const DriverType> driver_types() { return kDriverTypes; }

std::unique_ptr<io::Driver> make_driver(const config::ConfigNode& node) {
  return make_plugin(driver_types(), "driver", node);
}

}  // namespace leakmon::daemon
