#include "io/can/signal.hpp"

#include <cmath>
#include <string>

namespace leakmon::io::can {
namespace {

constexpr unsigned kPayloadBits = kFdMaxLength * 8;

// Motorola signals are contiguous when the payload is read as one big-endian bit string
// (bit 0 = MSB of byte 0). This is the position of the signal's MSB in that string.
unsigned motorola_msb_position(unsigned start_bit) {
  return (start_bit / 8) * 8 + 7 - start_bit % 8;
}

// First and one-past-last bit of the signal in its own contiguous numbering.
unsigned first_bit(const SignalLayout& layout) {
  return layout.byte_order == ByteOrder::intel ? layout.start_bit
                                               : motorola_msb_position(layout.start_bit);
}

}  // namespace

std::string layout_problem(const SignalLayout& layout) {
  if (layout.length < 1 || layout.length > 64) {
    return "length must be 1..64 bits, got " + std::to_string(layout.length);
  }
  if (layout.start_bit >= kPayloadBits) {
    return "start_bit must be 0..511, got " + std::to_string(layout.start_bit);
  }
  if (first_bit(layout) + layout.length > kPayloadBits) {
    return "signal runs past the end of a 64-byte payload (start_bit " +
           std::to_string(layout.start_bit) + ", length " + std::to_string(layout.length) +
           (layout.byte_order == ByteOrder::motorola ? ", motorola)" : ", intel)");
  }
  const std::uint32_t id_mask = layout.extended ? kExtendedIdMask : kStandardIdMask;
  if ((layout.id & ~id_mask) != 0) {
    return layout.extended ? "extended id must fit in 29 bits (max 0x1FFFFFFF)"
                           : "standard id must fit in 11 bits (max 0x7FF); set extended: true "
                             "for a 29-bit id";
  }
  if (!std::isfinite(layout.factor) || layout.factor == 0.0)
    return "factor must be finite and non-zero";
  if (!std::isfinite(layout.offset)) return "offset must be finite";
  return {};
}

unsigned bytes_needed(const SignalLayout& layout) {
  return (first_bit(layout) + layout.length + 7) / 8;
}

std::int64_t extract_raw(const SignalLayout& layout, const CanFrame& frame) noexcept {
  const unsigned first = first_bit(layout);
  std::uint64_t raw = 0;
  if (layout.byte_order == ByteOrder::intel) {
    // LSB-first: payload bit b is bit b%8 of byte b/8; the signal's bit i is payload bit first+i.
    for (unsigned i = 0; i < layout.length; ++i) {
      const unsigned bit = first + i;
      const std::uint64_t value = (frame.data[bit / 8] >> (bit % 8)) & 1U;
      raw |= value << i;
    }
  } else {
    // MSB-first: big-endian bit p is bit 7 - p%8 of byte p/8.
    for (unsigned i = 0; i < layout.length; ++i) {
      const unsigned bit = first + i;
      raw = (raw << 1) | ((frame.data[bit / 8] >> (7 - bit % 8)) & 1U);
    }
  }
  if (layout.is_signed && layout.length < 64 && ((raw >> (layout.length - 1)) & 1U) != 0) {
    raw |= ~std::uint64_t{0} << layout.length;  // two's complement sign extension
  }
  return static_cast<std::int64_t>(raw);
}

bool decode(const SignalLayout& layout, const CanFrame& frame, double& value) noexcept {
  if (frame.error || frame.remote || frame.id != layout.id || frame.extended != layout.extended) {
    return false;
  }
  if (frame.length < bytes_needed(layout)) return false;
  const std::int64_t raw = extract_raw(layout, frame);
  const double scaled = layout.is_signed ? static_cast<double>(raw)
                                         : static_cast<double>(static_cast<std::uint64_t>(raw));
  value = scaled * layout.factor + layout.offset;
  return true;
}

}  // namespace leakmon::io::can
