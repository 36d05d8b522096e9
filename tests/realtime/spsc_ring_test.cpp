#include "realtime/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <thread>

namespace leakmon::realtime {
namespace {

TEST(SpscRing, HoldsExactlyItsCapacityAndKeepsOrder) {
  SpscRing<int> ring(3);
  EXPECT_TRUE(ring.empty());
  EXPECT_TRUE(ring.try_push(1));
  EXPECT_TRUE(ring.try_push(2));
  EXPECT_TRUE(ring.try_push(3));
  EXPECT_FALSE(ring.try_push(4)) << "a full ring must refuse, not overwrite";
  EXPECT_EQ(ring.size(), 3u);
  int value = 0;
  ASSERT_TRUE(ring.try_pop(value));
  EXPECT_EQ(value, 1);
  EXPECT_TRUE(ring.try_push(4));
  for (int expected : {2, 3, 4}) {
    ASSERT_TRUE(ring.try_pop(value));
    EXPECT_EQ(value, expected);
  }
  EXPECT_FALSE(ring.try_pop(value));
  EXPECT_EQ(ring.front(), nullptr);
}

TEST(SpscRing, RejectsCapacitiesItCannotIndex) {
  EXPECT_THROW(SpscRing<int>(0), std::invalid_argument);
  // capacity + 1 slots would wrap the index arithmetic (or the allocation size). Braces: with
  // parentheses Clang reads the statement as a declaration of a variable named `...::max`.
  EXPECT_THROW(SpscRing<int>{std::numeric_limits<std::size_t>::max()}, std::invalid_argument);
  EXPECT_THROW(SpscRing<std::uint64_t>(std::numeric_limits<std::ptrdiff_t>::max() / 8),
               std::invalid_argument);
  const SpscRing<int> one(1);
  EXPECT_EQ(one.capacity(), 1u);
}

TEST(SpscRing, WrapsAroundManyTimes) {
  SpscRing<std::uint64_t> ring(5);
  std::uint64_t next_in = 0, next_out = 0;
  for (int round = 0; round < 1000; ++round) {
    while (ring.try_push(next_in)) ++next_in;
    EXPECT_EQ(ring.size(), 5u);
    for (int k = 0; k < 3; ++k) {
      std::uint64_t v = 0;
      ASSERT_TRUE(ring.try_pop(v));
      ASSERT_EQ(v, next_out++);
    }
  }
}

// Producer and consumer on two threads, with a payload large enough that a torn read (slot
// read while being written) shows as mismatched fields. Run under TSan in CI (THREADS).
struct Payload {
  std::uint64_t sequence = 0;
  std::uint64_t check[7] = {};
};

TEST(SpscRing, TwoThreadStressLosesNothingAndTearsNothing) {
  constexpr std::uint64_t kCount = 300000;
  SpscRing<Payload> ring(64);
  std::uint64_t refused = 0;
  std::thread producer([&] {
    Payload p;
    for (std::uint64_t i = 0; i < kCount;) {
      p.sequence = i;
      for (auto& c : p.check) c = i * 2654435761u;
      if (ring.try_push(p)) {
        ++i;
      } else {
        ++refused;
        std::this_thread::yield();
      }
    }
  });
  std::uint64_t expected = 0;
  bool torn = false;
  while (expected < kCount) {
    Payload* p = ring.front();
    if (p == nullptr) {
      std::this_thread::yield();
      continue;
    }
    if (p->sequence != expected) break;
    for (auto c : p->check) torn |= c != expected * 2654435761u;
    ring.pop();
    ++expected;
  }
  producer.join();
  EXPECT_EQ(expected, kCount) << "elements lost or reordered";
  EXPECT_FALSE(torn);
  EXPECT_TRUE(ring.empty());
}

}  // namespace
}  // namespace leakmon::realtime
