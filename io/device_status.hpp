// Device status in the four NAMUR NE 107 categories (plus "ok") that every operator station
// understands: used for drivers (connection health) and for each channel (sensor plausibility).
#pragma once

#include <cstdint>
#include <string_view>

namespace leakmon::io {

enum class DeviceStatus : std::uint8_t {
  ok,                    // NE 107 "good": valid output
  failure,               // output invalid (frozen, dropped out, disconnected, bus-off)
  function_check,        // output temporarily invalid by intent (starting, connecting, learning)
  out_of_specification,  // outside its range or specification (saturated, spiking)
  maintenance_required,  // still valid, but degrading (repeated errors, reconnects)
};

constexpr std::string_view to_string(DeviceStatus status) {
  switch (status) {
    case DeviceStatus::ok:
      return "ok";
    case DeviceStatus::failure:
      return "failure";
    case DeviceStatus::function_check:
      return "function_check";
    case DeviceStatus::out_of_specification:
      return "out_of_specification";
    case DeviceStatus::maintenance_required:
      return "maintenance_required";
  }
  return "unknown";
}

}  // namespace leakmon::io
