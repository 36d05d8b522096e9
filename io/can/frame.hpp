// One CAN or CAN FD frame as leakmon sees it, whichever source it came from (a SocketCAN
// socket or a line of a candump log). Flags live in their own fields rather than in the id's
// top bits (as struct can_frame keeps them), so that decoding never has to mask them out.
#pragma once

#include <array>
#include <cstdint>

namespace leakmon::io::can {

inline constexpr std::uint32_t kStandardIdMask = 0x7FF;       // 11-bit identifier
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFFFFFF;  // 29-bit identifier
inline constexpr std::size_t kClassicMaxLength = 8;
inline constexpr std::size_t kFdMaxLength = 64;

struct CanFrame {
  std::uint32_t id = 0;       // without flags; for an error frame the CAN_ERR_* class bits
  bool extended = false;      // 29-bit identifier
  bool remote = false;        // remote transmission request: carries no data
  bool error = false;         // error frame synthesised by the CAN controller driver
  bool fd = false;            // CAN FD frame
  std::uint8_t fd_flags = 0;  // CANFD_BRS (1), CANFD_ESI (2)
  std::uint8_t length = 0;    // data bytes; for a remote frame the requested length
  std::array<std::uint8_t, kFdMaxLength> data{};
};

}  // namespace leakmon::io::can
