// One tick of a sampling group: every channel of the group's drivers, as the loop read them.
// Fixed size so that the ring buffer's slots are allocated once and the loop copies plain data.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace leakmon::realtime {

// Channels per sampling group; a configuration with more is rejected when loaded.
inline constexpr std::size_t kMaxGroupChannels = 32;

struct Sample {
  std::uint64_t tick = 0;         // tick index since the group started (gaps = missed cycles)
  std::int64_t monotonic_ns = 0;  // when the loop read the drivers (simulated under replay)
  double t = 0.0;  // source time [s]: the capture's t under replay, else ticks * period
  std::uint32_t channel_count = 0;
  std::array<double, kMaxGroupChannels> values{};  // NaN marks a gap
};

}  // namespace leakmon::realtime
