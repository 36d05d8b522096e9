// A signal defined the way a DBC file defines it: where its bits sit in one frame's payload,
// how to read them (byte order, sign) and how to scale them to physical units.
//
// Bit numbering is DBC's. Intel (little endian, `@1`): `start_bit` is the least significant
// bit, counted LSB-first through the payload (bit b is bit b%8 of byte b/8) and the signal runs
// upwards from it. Motorola (big endian, `@0`): `start_bit` is the *most* significant bit in
// the same per-byte numbering, and the signal runs towards less significant bits, continuing
// at bit 7 of the next byte after bit 0 of one byte (DBC's "sawtooth").
#pragma once

#include <cstdint>
#include <string>

#include "io/can/frame.hpp"

namespace leakmon::io::can {

enum class ByteOrder { intel, motorola };

struct SignalLayout {
  std::uint32_t id = 0;
  bool extended = false;
  unsigned start_bit = 0;
  unsigned length = 1;  // 1..64 bits
  ByteOrder byte_order = ByteOrder::intel;
  bool is_signed = false;
  double factor = 1.0;
  double offset = 0.0;
};

// Why `layout` cannot be decoded from any frame (empty when it can): length outside 1..64,
// bits beyond a 64-byte CAN FD payload, an identifier too wide for its format, a zero or
// non-finite factor.
std::string layout_problem(const SignalLayout& layout);

// Payload bytes a frame must carry for `layout` to be decodable. `layout` must be valid.
unsigned bytes_needed(const SignalLayout& layout);

// The raw bits of `layout` in `frame`, sign-extended when the signal is signed. The frame must
// carry at least bytes_needed(layout) bytes.
std::int64_t extract_raw(const SignalLayout& layout, const CanFrame& frame) noexcept;

// Physical value raw * factor + offset, or false when `frame` is too short, has no data
// (remote or error frame) or does not carry this signal's identifier.
bool decode(const SignalLayout& layout, const CanFrame& frame, double& value) noexcept;

}  // namespace leakmon::io::can
