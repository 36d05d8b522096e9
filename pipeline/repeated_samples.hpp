// Notices an acquisition that delivers new values slower than it samples: a Modbus device that
// updates its registers at 250 Hz polled at 500 Hz, an RTU link that needs 10 ms a request. The
// loop then hands the worker the same response twice or more, and the repeats act as a
// zero-order hold that reshapes the 62-125 Hz band the leak features live in: a healthy rig fed
// every other sample twice raised a false leak alarm within 20 s (pressure-only detector).
//
// A repeat is a sample whose every acquired channel equals the sample before it exactly. With
// two or more channels that carry transducer noise (or a command), that is rare on a healthy
// stream: each 12-bit pressure repeats its previous reading with a probability of about 0.3 even
// at rest with 1 LSB of noise, so both together about 0.1, and the hydraulic mode makes it far
// rarer while the rig moves. A fifth of the last second repeating is therefore no healthy
// stream; one channel alone cannot tell a quiet transducer from a held one, so it is not judged.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace leakmon::pipeline {

class RepeatedSampleCheck {
 public:
  static constexpr std::size_t kWindow = 500;  // samples judged together (1 s at 500 Hz)
  static constexpr std::size_t kRaise = 100;   // repeats in the window that make it repeating
  static constexpr std::size_t kClear = 50;    // ... and that it must fall below again
  static constexpr std::size_t kMaxChannels = 8;

  // values: this sample's raw channels (NaN for a gap). Returns whether the stream is repeating.
  bool push(std::span<const double> values) noexcept {
    const std::size_t n = values.size() < kMaxChannels ? values.size() : kMaxChannels;
    bool repeat = n >= 2 && previous_size_ == n;
    for (std::size_t i = 0; i < n; ++i) {
      // A gap is no repeat; NaN != NaN already says so.
      repeat = repeat && values[i] == previous_[i];
      previous_[i] = values[i];
    }
    previous_size_ = n;
    count_ -= flags_[next_];
    flags_[next_] = repeat ? 1 : 0;
    count_ += flags_[next_];
    next_ = (next_ + 1) % kWindow;
    if (!repeating_ && count_ >= kRaise) repeating_ = true;
    if (repeating_ && count_ < kClear) repeating_ = false;
    return repeating_;
  }

  bool repeating() const { return repeating_; }
  // Repeats among the last kWindow samples.
  std::size_t repeats() const { return count_; }

 private:
  std::array<double, kMaxChannels> previous_{};
  std::size_t previous_size_ = 0;
  std::array<std::uint8_t, kWindow> flags_{};
  std::size_t next_ = 0;
  std::size_t count_ = 0;
  bool repeating_ = false;
};

}  // namespace leakmon::pipeline
