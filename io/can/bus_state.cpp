#include "io/can/bus_state.hpp"

#include <linux/can/error.h>

namespace leakmon::io::can {

const char* to_string(BusState state) {
  switch (state) {
    case BusState::active:
      return "ok";
    case BusState::warning:
      return "error-warning";
    case BusState::passive:
      return "error-passive";
    case BusState::bus_off:
      return "bus-off";
  }
  return "unknown";
}

DeviceStatus device_status(BusState state) noexcept {
  switch (state) {
    case BusState::active:
      return DeviceStatus::ok;
    case BusState::warning:
    case BusState::passive:
      return DeviceStatus::maintenance_required;
    case BusState::bus_off:
      return DeviceStatus::failure;
  }
  return DeviceStatus::failure;
}

ErrorFrameEffect interpret_error_frame(const CanFrame& frame) noexcept {
  ErrorFrameEffect effect;
  const std::uint32_t classes = frame.id;
  const std::uint8_t controller = frame.length > 1 ? frame.data[1] : 0;
  // Least severe first, so that the description ends up naming the most severe class.
  if (classes & CAN_ERR_LOSTARB) effect.description = "lost arbitration";
  if (classes & CAN_ERR_ACK) effect.description = "no acknowledgement on transmission";
  if (classes & CAN_ERR_PROT) effect.description = "protocol violation";
  if (classes & CAN_ERR_TRX) effect.description = "transceiver error";
  if (classes & CAN_ERR_TX_TIMEOUT) effect.description = "transmit timeout";
  if (classes & CAN_ERR_BUSERROR) effect.description = "bus error";
  if (classes & CAN_ERR_CRTL) {
    if (controller & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) {
      effect.controller_overflow = true;
      effect.description = "controller buffer overflow";
    }
    if (controller & CAN_ERR_CRTL_ACTIVE) {
      effect.changes_state = true;
      effect.state = BusState::active;
      effect.description = "controller back to error-active";
    }
    if (controller & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) {
      effect.changes_state = true;
      effect.state = BusState::warning;
      effect.description = "controller error-warning";
    }
    if (controller & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      effect.changes_state = true;
      effect.state = BusState::passive;
      effect.description = "controller error-passive";
    }
  }
  if (classes & CAN_ERR_RESTARTED) {
    effect.changes_state = true;
    effect.state = BusState::active;
    effect.description = "controller restarted";
  }
  if (classes & CAN_ERR_BUSOFF) {
    effect.changes_state = true;
    effect.state = BusState::bus_off;
    effect.description = "bus-off";
  }
  if (*effect.description == '\0') effect.description = "error frame";
  return effect;
}

}  // namespace leakmon::io::can
