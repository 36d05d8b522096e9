#include "io/can/frame_decoder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "tests/support/alloc_counter.hpp"

namespace leakmon::io::can {
namespace {

constexpr std::int64_t kMs = 1'000'000;

SignalDef signal(const char* channel, std::uint32_t id, unsigned start, unsigned length,
                 std::int64_t max_age_ns = 10 * kMs) {
  SignalDef d;
  d.channel = channel;
  d.layout.id = id;
  d.layout.start_bit = start;
  d.layout.length = length;
  d.max_age_ns = max_age_ns;
  return d;
}

CanFrame frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  for (auto b : bytes) f.data[f.length++] = b;
  return f;
}

TEST(FrameDecoder, RoutesEachFrameToItsSignalsAndKeepsChannelOrder) {
  // p2 and p1 share 0x200, x sits on 0x100: the output order is the configuration's.
  FrameDecoder decoder(
      {signal("p2", 0x200, 16, 16), signal("x", 0x100, 0, 8), signal("p1", 0x200, 0, 16)});
  std::vector<double> v(3);
  EXPECT_EQ(decoder.sample(v, 0), 0U);
  for (double x : v) EXPECT_TRUE(std::isnan(x)) << "nothing received yet";

  EXPECT_EQ(decoder.apply(frame(0x200, {0x01, 0x00, 0x02, 0x00}), 1 * kMs), 2U);
  EXPECT_EQ(decoder.apply(frame(0x300, {0xFF}), 1 * kMs), 0U) << "unconfigured id";
  decoder.sample(v, 2 * kMs);
  EXPECT_EQ(v[0], 2.0);
  EXPECT_TRUE(std::isnan(v[1]));
  EXPECT_EQ(v[2], 1.0);

  EXPECT_EQ(decoder.apply(frame(0x100, {0x2A}), 3 * kMs), 1U);
  decoder.sample(v, 4 * kMs);
  EXPECT_EQ(v[1], 42.0);
  EXPECT_EQ(decoder.decoded_frames(), 2U);
}

TEST(FrameDecoder, ValuesOlderThanTheirMaxAgeBecomeGaps) {
  FrameDecoder decoder({signal("p1", 0x10, 0, 8, 5 * kMs), signal("p2", 0x11, 0, 8, 50 * kMs)});
  decoder.apply(frame(0x10, {7}), 100 * kMs);
  decoder.apply(frame(0x11, {9}), 100 * kMs);
  std::vector<double> v(2);
  EXPECT_EQ(decoder.sample(v, 105 * kMs), 0U);
  EXPECT_EQ(v[0], 7.0) << "exactly max age old is still fresh";
  EXPECT_EQ(decoder.sample(v, 106 * kMs), 1U);
  EXPECT_TRUE(std::isnan(v[0]));
  EXPECT_EQ(v[1], 9.0);
  decoder.apply(frame(0x10, {8}), 106 * kMs);
  EXPECT_EQ(decoder.sample(v, 107 * kMs), 0U);
  EXPECT_EQ(v[0], 8.0) << "a new frame ends the gap";
}

TEST(FrameDecoder, ShortFramesAreCountedAndKeepTheOldValue) {
  FrameDecoder decoder({signal("p1", 0x10, 0, 8), signal("p2", 0x10, 8, 16)});
  decoder.apply(frame(0x10, {1, 2, 3}), 0);
  EXPECT_EQ(decoder.apply(frame(0x10, {5, 6}), 1 * kMs), 1U) << "p1 fits, p2 does not";
  EXPECT_EQ(decoder.short_frames(), 1U);
  std::vector<double> v(2);
  decoder.sample(v, 2 * kMs);
  EXPECT_EQ(v[0], 5.0);
  EXPECT_EQ(v[1], 0x0302) << "p2 keeps its last good value";
}

TEST(FrameDecoder, ErrorAndRemoteFramesCarryNoValues) {
  FrameDecoder decoder({signal("p1", 0x10, 0, 8)});
  CanFrame remote = frame(0x10, {});
  remote.remote = true;
  remote.length = 1;
  EXPECT_EQ(decoder.apply(remote, 0), 0U);
  CanFrame error = frame(0x10, {1});
  error.error = true;
  EXPECT_EQ(decoder.apply(error, 0), 0U);
  EXPECT_EQ(decoder.short_frames(), 0U);
}

TEST(FrameDecoder, RejectsInvalidLayouts) {
  EXPECT_THROW(FrameDecoder({signal("p1", 0x10, 0, 65)}), std::invalid_argument);
}

TEST(FrameDecoder, ApplyAndSampleAllocateNothing) {
  std::vector<SignalDef> defs;
  for (unsigned i = 0; i < 16; ++i) {
    defs.push_back(signal("c", 0x100 + i % 4, (i / 4) * 16, 16));
    defs.back().channel += std::to_string(i);
  }
  FrameDecoder decoder(std::move(defs));
  std::vector<double> v(16);
  CanFrame f = frame(0x100, {1, 2, 3, 4, 5, 6, 7, 8});
  test::AllocationScope scope;
  for (std::int64_t t = 0; t < 1000; ++t) {
    f.id = 0x100 + static_cast<std::uint32_t>(t % 5);  // 0x104 is not configured
    decoder.apply(f, t * kMs);
    decoder.sample(v, t * kMs);
  }
  EXPECT_EQ(scope.count(), 0U);
  EXPECT_EQ(v[0], 0x0201);
}

}  // namespace
}  // namespace leakmon::io::can
