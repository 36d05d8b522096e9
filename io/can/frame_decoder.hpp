// Turns a stream of received frames into the newest value of each configured signal, and each
// tick into one value per channel. Shared by the SocketCAN driver and the candump replay, so a
// captured log decodes exactly as the live bus did.
//
// Everything after construction is real-time safe: apply() and sample() touch only storage
// sized in the constructor, and the identifier lookup is a binary search in a sorted table.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/can/frame.hpp"
#include "io/can/signal.hpp"

namespace leakmon::io::can {

struct SignalDef {
  std::string channel;  // the channel name the daemon sees
  std::string unit;     // informational (e.g. "Pa")
  SignalLayout layout;
  std::int64_t max_age_ns = 0;  // a value older than this at sampling time is a gap
};

class FrameDecoder {
 public:
  // `signals` must have valid layouts (layout_problem() empty); throws std::invalid_argument
  // otherwise.
  explicit FrameDecoder(std::vector<SignalDef> signals);

  const std::vector<SignalDef>& signals() const { return signals_; }

  // Decodes every signal that `frame` carries, stamping each with `received_ns`. Returns how
  // many signals took a new value. A data frame that has a configured id but is too short for
  // one of its signals counts in short_frames() and leaves that value unchanged.
  std::size_t apply(const CanFrame& frame, std::int64_t received_ns) noexcept;

  // One value per signal, in signals() order: the newest value, or NaN when none was ever
  // received or it is older than its max age at `now_ns`. Returns how many were stale (had a
  // value, but too old).
  std::size_t sample(std::span<double> values, std::int64_t now_ns) const noexcept;

  std::uint64_t short_frames() const { return short_frames_; }
  std::uint64_t decoded_frames() const { return decoded_frames_; }

  // Forget every value (e.g. after a restart of the source).
  void clear() noexcept;

 private:
  struct IdRange {
    std::uint64_t key;        // id | extended << 32, the sort key
    std::uint32_t first = 0;  // index into order_
    std::uint32_t count = 0;
  };
  static std::uint64_t key_of(std::uint32_t id, bool extended) {
    return std::uint64_t{id} | (std::uint64_t{extended} << 32);
  }

  std::vector<SignalDef> signals_;
  std::vector<std::uint32_t> order_;  // signal indices grouped by identifier
  std::vector<IdRange> ranges_;       // sorted by key
  std::vector<double> value_;
  std::vector<std::int64_t> received_ns_;
  std::vector<char> has_value_;
  std::uint64_t short_frames_ = 0;
  std::uint64_t decoded_frames_ = 0;
};

}  // namespace leakmon::io::can
