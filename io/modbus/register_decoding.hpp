// Register words -> number, for the data types and byte orders rig engineers know from Telegraf
// and collectd. A register is a 16-bit word sent high byte first; devices disagree on how
// multi-register values are laid out, so the layout is named by the letters of a big-endian
// value: ABCD = as sent (Motorola), CDAB = word-swapped, BADC = byte-swapped within each word,
// DCBA = fully reversed (Intel). For 64-bit values the same rule extends to four words (CDAB:
// last word first, bytes within words as sent); for 16-bit values only the byte swap matters.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace leakmon::io::modbus {

enum class DataType { int16, uint16, int32, uint32, float32, float64 };
enum class ByteOrder { abcd, cdab, badc, dcba };

// Registers one value of `type` occupies: 1, 2 or 4.
std::size_t register_count(DataType type);

// `words` holds register_count(type) registers in the order the device sent them; fewer words
// give NaN (callers size them from register_count, so this only guards malformed input).
double decode_registers(std::span<const std::uint16_t> words, DataType type, ByteOrder order);

// The inverse, for alarm outputs that write a register: the value is rounded and saturated to
// the integer types; `words` must hold register_count(type) registers.
void encode_registers(double value, DataType type, ByteOrder order, std::span<std::uint16_t> words);

// Names as written in configuration: INT16 UINT16 INT32 UINT32 FLOAT32 FLOAT64 and ABCD CDAB
// BADC DCBA (upper case, as in Telegraf).
std::optional<DataType> parse_data_type(std::string_view name);
std::optional<ByteOrder> parse_byte_order(std::string_view name);
std::string_view to_string(DataType type);
std::string_view to_string(ByteOrder order);

}  // namespace leakmon::io::modbus
