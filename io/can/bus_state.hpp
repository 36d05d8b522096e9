// What the CAN controller says about the bus, read from error frames (linux/can/error.h): the
// controller's fault-confinement state, plus counts an operator wants as metrics. A fault on
// the bus is a communication problem, never a measurement: it changes this state and the
// driver's health, and silenced signals become gaps through their max age.
#pragma once

#include <cstdint>

#include "io/can/frame.hpp"
#include "io/device_status.hpp"

namespace leakmon::io::can {

enum class BusState : std::uint8_t { active, warning, passive, bus_off };

const char* to_string(BusState state);
// NE 107: error-active is good; error-warning and error-passive still deliver frames but the
// bus is degrading (maintenance required); bus-off delivers nothing (failure).
DeviceStatus device_status(BusState state) noexcept;

struct ErrorFrameEffect {
  bool changes_state = false;
  BusState state = BusState::active;  // the new state when changes_state
  bool controller_overflow = false;   // the controller's own receive/transmit buffer overflowed
  const char* description = "";       // static text naming the most severe class in the frame
};

// Interprets one error frame (frame.error must be set; frame.id holds the CAN_ERR_* classes).
ErrorFrameEffect interpret_error_frame(const CanFrame& frame) noexcept;

}  // namespace leakmon::io::can
