#include "io/modbus/register_decoding.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>

namespace leakmon::io::modbus {
namespace {

constexpr std::array<std::string_view, 6> kDataTypeNames = {"INT16",  "UINT16",  "INT32",
                                                            "UINT32", "FLOAT32", "FLOAT64"};
constexpr std::array<std::string_view, 4> kByteOrderNames = {"ABCD", "CDAB", "BADC", "DCBA"};

bool words_reversed(ByteOrder order) {
  return order == ByteOrder::cdab || order == ByteOrder::dcba;
}
bool bytes_swapped(ByteOrder order) { return order == ByteOrder::badc || order == ByteOrder::dcba; }

std::uint16_t swap_bytes(std::uint16_t word) {
  return static_cast<std::uint16_t>((word << 8U) | (word >> 8U));
}

// The value's bits, most significant word first, whatever order the device sent them in.
std::uint64_t assemble(std::span<const std::uint16_t> words, ByteOrder order) {
  std::uint64_t bits = 0;
  const std::size_t n = words.size();
  for (std::size_t i = 0; i < n; ++i) {
    std::uint16_t word = words[words_reversed(order) ? n - 1 - i : i];
    if (bytes_swapped(order)) word = swap_bytes(word);
    bits = (bits << 16U) | word;
  }
  return bits;
}

void disassemble(std::uint64_t bits, ByteOrder order, std::span<std::uint16_t> words) {
  const std::size_t n = words.size();
  for (std::size_t i = 0; i < n; ++i) {
    auto word = static_cast<std::uint16_t>(bits >> (16U * (n - 1 - i)));
    if (bytes_swapped(order)) word = swap_bytes(word);
    words[words_reversed(order) ? n - 1 - i : i] = word;
  }
}

template <typename Int>
Int saturate(double value) {
  if (std::isnan(value)) return 0;
  const double rounded = std::nearbyint(value);
  if (rounded <= static_cast<double>(std::numeric_limits<Int>::min()))
    return std::numeric_limits<Int>::min();
  if (rounded >= static_cast<double>(std::numeric_limits<Int>::max()))
    return std::numeric_limits<Int>::max();
  return static_cast<Int>(rounded);
}

}  // namespace

std::size_t register_count(DataType type) {
  switch (type) {
    case DataType::int16:
    case DataType::uint16:
      return 1;
    case DataType::int32:
    case DataType::uint32:
    case DataType::float32:
      return 2;
    case DataType::float64:
      return 4;
  }
  return 1;
}

double decode_registers(std::span<const std::uint16_t> words, DataType type, ByteOrder order) {
  const std::size_t n = register_count(type);
  if (words.size() < n) return std::numeric_limits<double>::quiet_NaN();
  const std::uint64_t bits = assemble(words.first(n), order);
  switch (type) {
    case DataType::int16:
      return static_cast<std::int16_t>(static_cast<std::uint16_t>(bits));
    case DataType::uint16:
      return static_cast<std::uint16_t>(bits);
    case DataType::int32:
      return static_cast<std::int32_t>(static_cast<std::uint32_t>(bits));
    case DataType::uint32:
      return static_cast<std::uint32_t>(bits);
    case DataType::float32:
      return std::bit_cast<float>(static_cast<std::uint32_t>(bits));
    case DataType::float64:
      return std::bit_cast<double>(bits);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

void encode_registers(double value, DataType type, ByteOrder order,
                      std::span<std::uint16_t> words) {
  const std::size_t n = register_count(type);
  if (words.size() < n) return;
  std::uint64_t bits = 0;
  switch (type) {
    case DataType::int16:
      bits = static_cast<std::uint16_t>(saturate<std::int16_t>(value));
      break;
    case DataType::uint16:
      bits = saturate<std::uint16_t>(value);
      break;
    case DataType::int32:
      bits = static_cast<std::uint32_t>(saturate<std::int32_t>(value));
      break;
    case DataType::uint32:
      bits = saturate<std::uint32_t>(value);
      break;
    case DataType::float32:
      bits = std::bit_cast<std::uint32_t>(static_cast<float>(value));
      break;
    case DataType::float64:
      bits = std::bit_cast<std::uint64_t>(value);
      break;
  }
  disassemble(bits, order, words.first(n));
}

std::optional<DataType> parse_data_type(std::string_view name) {
  const auto* it = std::find(kDataTypeNames.begin(), kDataTypeNames.end(), name);
  if (it == kDataTypeNames.end()) return std::nullopt;
  return static_cast<DataType>(it - kDataTypeNames.begin());
}

std::optional<ByteOrder> parse_byte_order(std::string_view name) {
  const auto* it = std::find(kByteOrderNames.begin(), kByteOrderNames.end(), name);
  if (it == kByteOrderNames.end()) return std::nullopt;
  return static_cast<ByteOrder>(it - kByteOrderNames.begin());
}

std::string_view to_string(DataType type) { return kDataTypeNames[static_cast<std::size_t>(type)]; }
std::string_view to_string(ByteOrder order) {
  return kByteOrderNames[static_cast<std::size_t>(order)];
}

}  // namespace leakmon::io::modbus
