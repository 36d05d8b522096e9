#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "io/modbus/register_decoding.hpp"

namespace leakmon::io::modbus {
namespace {

double decode(std::vector<std::uint16_t> words, DataType type, ByteOrder order) {
  return decode_registers(words, type, order);
}

TEST(RegisterDecoding, Float32PiInEveryByteOrder) {
  // 3.14159274f = 0x40490FDB: A=0x40 B=0x49 C=0x0F D=0xDB.
  const double pi32 = static_cast<double>(3.14159274f);
  EXPECT_EQ(decode({0x4049, 0x0FDB}, DataType::float32, ByteOrder::abcd), pi32);
  EXPECT_EQ(decode({0x0FDB, 0x4049}, DataType::float32, ByteOrder::cdab), pi32);
  EXPECT_EQ(decode({0x4940, 0xDB0F}, DataType::float32, ByteOrder::badc), pi32);
  EXPECT_EQ(decode({0xDB0F, 0x4940}, DataType::float32, ByteOrder::dcba), pi32);
  EXPECT_NEAR(decode({0x4049, 0x0FDB}, DataType::float32, ByteOrder::abcd), 3.14159274, 1e-8);
}

TEST(RegisterDecoding, IntegersKnownVectors) {
  EXPECT_EQ(decode({0xFFFF}, DataType::int16, ByteOrder::abcd), -1.0);
  EXPECT_EQ(decode({0xFFFF}, DataType::uint16, ByteOrder::abcd), 65535.0);
  EXPECT_EQ(decode({0x8000}, DataType::int16, ByteOrder::abcd), -32768.0);
  EXPECT_EQ(decode({0x3412}, DataType::uint16, ByteOrder::badc), 0x1234);
  EXPECT_EQ(decode({0x3412}, DataType::uint16, ByteOrder::dcba), 0x1234);
  EXPECT_EQ(decode({0x1234}, DataType::uint16, ByteOrder::cdab), 0x1234);
  EXPECT_EQ(decode({0x1234, 0x5678}, DataType::uint32, ByteOrder::abcd), 0x12345678);
  EXPECT_EQ(decode({0x5678, 0x1234}, DataType::uint32, ByteOrder::cdab), 0x12345678);
  EXPECT_EQ(decode({0x3412, 0x7856}, DataType::uint32, ByteOrder::badc), 0x12345678);
  EXPECT_EQ(decode({0x7856, 0x3412}, DataType::uint32, ByteOrder::dcba), 0x12345678);
  EXPECT_EQ(decode({0xFFFF, 0xFFFE}, DataType::int32, ByteOrder::abcd), -2.0);
  EXPECT_EQ(decode({0xFFFE, 0xFFFF}, DataType::int32, ByteOrder::cdab), -2.0);
  EXPECT_EQ(decode({0xFFFF, 0xFFFF}, DataType::uint32, ByteOrder::abcd), 4294967295.0);
}

TEST(RegisterDecoding, Float64KnownVectors) {
  // 1.0 = 0x3FF0000000000000; -2.5 = 0xC004000000000000.
  EXPECT_EQ(decode({0x3FF0, 0, 0, 0}, DataType::float64, ByteOrder::abcd), 1.0);
  EXPECT_EQ(decode({0, 0, 0, 0x3FF0}, DataType::float64, ByteOrder::cdab), 1.0);
  EXPECT_EQ(decode({0xF03F, 0, 0, 0}, DataType::float64, ByteOrder::badc), 1.0);
  EXPECT_EQ(decode({0, 0, 0, 0xF03F}, DataType::float64, ByteOrder::dcba), 1.0);
  EXPECT_EQ(decode({0xC004, 0, 0, 0}, DataType::float64, ByteOrder::abcd), -2.5);
  // 0x400921FB54442D18 = pi in double precision.
  EXPECT_EQ(decode({0x4009, 0x21FB, 0x5444, 0x2D18}, DataType::float64, ByteOrder::abcd), M_PI);
  EXPECT_EQ(decode({0x2D18, 0x5444, 0x21FB, 0x4009}, DataType::float64, ByteOrder::cdab), M_PI);
  EXPECT_EQ(decode({0x182D, 0x4454, 0xFB21, 0x0940}, DataType::float64, ByteOrder::dcba), M_PI);
}

TEST(RegisterDecoding, TooFewWordsIsAGapNotACrash) {
  EXPECT_TRUE(std::isnan(decode({0x4049}, DataType::float32, ByteOrder::abcd)));
  EXPECT_TRUE(std::isnan(decode({}, DataType::uint16, ByteOrder::abcd)));
  EXPECT_TRUE(std::isnan(decode({1, 2, 3}, DataType::float64, ByteOrder::dcba)));
}

TEST(RegisterDecoding, EncodeInvertsDecodeForEveryTypeAndOrder) {
  const std::array types = {DataType::int16,  DataType::uint16,  DataType::int32,
                            DataType::uint32, DataType::float32, DataType::float64};
  const std::array orders = {ByteOrder::abcd, ByteOrder::cdab, ByteOrder::badc, ByteOrder::dcba};
  const std::array values = {0.0, 1.0, 1234.0, 30000.0};
  for (DataType type : types)
    for (ByteOrder order : orders)
      for (double value : values) {
        std::array<std::uint16_t, 4> words{};
        encode_registers(value, type, order, words);
        EXPECT_EQ(decode_registers(words, type, order), value)
            << to_string(type) << " " << to_string(order);
      }
}

TEST(RegisterDecoding, EncodeSaturatesIntegers) {
  std::array<std::uint16_t, 2> words{};
  encode_registers(1e9, DataType::int16, ByteOrder::abcd, words);
  EXPECT_EQ(words[0], 0x7FFF);
  encode_registers(-5.0, DataType::uint32, ByteOrder::abcd, words);
  EXPECT_EQ(decode_registers(words, DataType::uint32, ByteOrder::abcd), 0.0);
}

TEST(RegisterDecoding, NamesRoundTripAndRejectUnknown) {
  EXPECT_EQ(parse_data_type("FLOAT32"), DataType::float32);
  EXPECT_EQ(parse_byte_order("CDAB"), ByteOrder::cdab);
  EXPECT_FALSE(parse_data_type("float32").has_value());
  EXPECT_FALSE(parse_data_type("REAL").has_value());
  EXPECT_FALSE(parse_byte_order("ABDC").has_value());
  EXPECT_EQ(to_string(DataType::int32), "INT32");
  EXPECT_EQ(to_string(ByteOrder::dcba), "DCBA");
  EXPECT_EQ(register_count(DataType::float64), 4U);
  EXPECT_EQ(register_count(DataType::uint32), 2U);
  EXPECT_EQ(register_count(DataType::int16), 1U);
}

}  // namespace
}  // namespace leakmon::io::modbus
