// DBC-style signal extraction against the DBC definition written out bit by bit (the Motorola
// "sawtooth" walk), plus hand-checked vectors from the DBC bit-numbering convention.
#include "io/can/signal.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace leakmon::io::can {
namespace {

CanFrame frame_with(std::uint32_t id, std::vector<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.length = static_cast<std::uint8_t>(bytes.size());
  f.fd = bytes.size() > 8;
  for (std::size_t i = 0; i < bytes.size(); ++i) f.data[i] = bytes[i];
  return f;
}

// The DBC definition, literally: the payload bits the signal occupies, MSB first for Motorola
// (start bit is the MSB; after bit 0 of a byte comes bit 7 of the next byte), LSB first for
// Intel (start bit is the LSB; bits count upwards through the bytes).
std::vector<unsigned> dbc_bit_positions(const SignalLayout& s) {
  std::vector<unsigned> bits;
  unsigned b = s.start_bit;
  for (unsigned i = 0; i < s.length; ++i) {
    bits.push_back(b);
    if (s.byte_order == ByteOrder::intel) {
      ++b;
    } else {
      b = (b % 8 == 0) ? b + 15 : b - 1;
    }
  }
  return bits;  // intel: LSB first; motorola: MSB first
}

void encode_reference(const SignalLayout& s, std::uint64_t raw, CanFrame& f) {
  const auto bits = dbc_bit_positions(s);
  for (unsigned i = 0; i < s.length; ++i) {
    const unsigned value_bit = s.byte_order == ByteOrder::intel ? i : s.length - 1 - i;
    const unsigned b = bits[i];
    const auto mask = static_cast<std::uint8_t>(1U << (b % 8));
    if ((raw >> value_bit) & 1U) {
      f.data[b / 8] = static_cast<std::uint8_t>(f.data[b / 8] | mask);
    } else {
      f.data[b / 8] = static_cast<std::uint8_t>(f.data[b / 8] & ~mask);
    }
  }
}

TEST(CanSignal, HandCheckedIntelAndMotorolaVectors) {
  SignalLayout s;
  s.id = 0x101;
  double v = 0;

  s.start_bit = 0;
  s.length = 16;
  ASSERT_TRUE(decode(s, frame_with(0x101, {0x34, 0x12}), v));
  EXPECT_EQ(v, 0x1234);

  s.byte_order = ByteOrder::motorola;
  s.start_bit = 7;  // MSB of byte 0
  ASSERT_TRUE(decode(s, frame_with(0x101, {0x12, 0x34}), v));
  EXPECT_EQ(v, 0x1234);

  // 12 bits starting at bit 3 of byte 0 (its low nibble) and all of byte 1.
  s.start_bit = 3;
  s.length = 12;
  ASSERT_TRUE(decode(s, frame_with(0x101, {0xFA, 0xBC}), v));
  EXPECT_EQ(v, 0xABC);
  EXPECT_EQ(bytes_needed(s), 2U);

  s.byte_order = ByteOrder::intel;
  s.start_bit = 4;  // high nibble of byte 0 is the low nibble of the value
  ASSERT_TRUE(decode(s, frame_with(0x101, {0xC5, 0xAB}), v));
  EXPECT_EQ(v, 0xABC);

  // A 1-bit flag in the middle of byte 2.
  s.start_bit = 21;
  s.length = 1;
  ASSERT_TRUE(decode(s, frame_with(0x101, {0, 0, 0x20}), v));
  EXPECT_EQ(v, 1.0);
  ASSERT_TRUE(decode(s, frame_with(0x101, {0xFF, 0xFF, 0xDF}), v));
  EXPECT_EQ(v, 0.0);
}

TEST(CanSignal, SignedScaledAndFullWidth) {
  SignalLayout s;
  s.length = 16;
  s.is_signed = true;
  s.factor = 0.5;
  s.offset = 10.0;
  double v = 0;
  ASSERT_TRUE(decode(s, frame_with(0, {0xFF, 0xFF}), v));
  EXPECT_EQ(v, 9.5);  // raw -1
  ASSERT_TRUE(decode(s, frame_with(0, {0x00, 0x80}), v));
  EXPECT_EQ(v, -32768 * 0.5 + 10.0);
  s.is_signed = false;
  ASSERT_TRUE(decode(s, frame_with(0, {0x00, 0x80}), v));
  EXPECT_EQ(v, 32768 * 0.5 + 10.0);

  s = SignalLayout{};
  s.length = 64;
  ASSERT_TRUE(decode(s, frame_with(0, std::vector<std::uint8_t>(8, 0xFF)), v));
  EXPECT_EQ(v, 18446744073709551615.0);
  s.is_signed = true;
  ASSERT_TRUE(decode(s, frame_with(0, std::vector<std::uint8_t>(8, 0xFF)), v));
  EXPECT_EQ(v, -1.0);
}

TEST(CanSignal, MatchesTheBitByBitDbcDefinitionForRandomLayouts) {
  std::mt19937_64 rng(20261121);
  for (int trial = 0; trial < 20000; ++trial) {
    SignalLayout s;
    s.byte_order = (trial % 2) ? ByteOrder::motorola : ByteOrder::intel;
    s.length = 1 + static_cast<unsigned>(rng() % 64);
    s.start_bit = static_cast<unsigned>(rng() % 512);
    s.is_signed = (rng() % 2) != 0;
    if (!layout_problem(s).empty()) continue;
    CanFrame f;
    f.length = 64;
    for (auto& byte : f.data) byte = static_cast<std::uint8_t>(rng());
    const std::uint64_t raw = s.length == 64 ? rng() : rng() & ((std::uint64_t{1} << s.length) - 1);
    encode_reference(s, raw, f);
    std::int64_t expected = static_cast<std::int64_t>(raw);
    if (s.is_signed && s.length < 64 && ((raw >> (s.length - 1)) & 1U)) {
      expected = static_cast<std::int64_t>(raw) -
                 static_cast<std::int64_t>(std::uint64_t{1} << (s.length - 1)) -
                 static_cast<std::int64_t>(std::uint64_t{1} << (s.length - 1));
    }
    ASSERT_EQ(extract_raw(s, f), expected)
        << "start " << s.start_bit << " length " << s.length << " order "
        << (s.byte_order == ByteOrder::intel ? "intel" : "motorola");
    // The highest payload byte the reference touched is the last one needed.
    unsigned last_byte = 0;
    for (unsigned b : dbc_bit_positions(s)) last_byte = std::max(last_byte, b / 8);
    ASSERT_EQ(bytes_needed(s), last_byte + 1);
  }
}

TEST(CanSignal, RefusesFramesThatCannotCarryTheSignal) {
  SignalLayout s;
  s.id = 0x10;
  s.start_bit = 8;
  s.length = 16;
  double v = -7;
  EXPECT_FALSE(decode(s, frame_with(0x10, {1, 2}), v)) << "needs 3 bytes";
  EXPECT_FALSE(decode(s, frame_with(0x11, {1, 2, 3}), v)) << "other id";
  CanFrame extended = frame_with(0x10, {1, 2, 3});
  extended.extended = true;
  EXPECT_FALSE(decode(s, extended, v)) << "same number, 29-bit id";
  CanFrame remote = frame_with(0x10, {1, 2, 3});
  remote.remote = true;
  EXPECT_FALSE(decode(s, remote, v));
  EXPECT_EQ(v, -7) << "value untouched";
  EXPECT_TRUE(decode(s, frame_with(0x10, {1, 2, 3}), v));
  EXPECT_EQ(v, 0x0302);
}

TEST(CanSignal, LayoutProblemsAreNamed) {
  SignalLayout s;
  s.length = 0;
  EXPECT_NE(layout_problem(s).find("length"), std::string::npos);
  s.length = 16;
  s.start_bit = 504;  // intel: bits 504..519 run past byte 63
  EXPECT_NE(layout_problem(s).find("past the end"), std::string::npos);
  s.byte_order = ByteOrder::motorola;  // motorola from bit 504 (byte 63, bit 0) also runs past
  EXPECT_NE(layout_problem(s).find("past the end"), std::string::npos);
  s.start_bit = 511;
  s.length = 8;
  EXPECT_EQ(layout_problem(s), "");
  s.id = 0x800;
  EXPECT_NE(layout_problem(s).find("11 bits"), std::string::npos);
  s.extended = true;
  EXPECT_EQ(layout_problem(s), "");
  s.factor = 0;
  EXPECT_NE(layout_problem(s).find("factor"), std::string::npos);
}

}  // namespace
}  // namespace leakmon::io::can
