// The sliding-window detail features of ONE channel, fed many samples per call: the form for
// offline analysis of long captures (`leakmon features`) and the fastest single-channel path.
// Gives exactly the windows, values and gaps of StreamingFeatures(params, 1) pushed one sample at
// a time, and every coefficient by the same arithmetic in the same order as the batch transform.
//
// Why it is faster for one channel: StreamingFeatures computes one window at a time, and for
// one channel most of a window's work is its boundary coefficients (they read the mode's
// extension, so no window can reuse another's), done one scalar sum after another. Here
// kLanes consecutive windows are computed together, window w in SIMD lane w; every lane sums
// each coefficient in the batch transform's order, so vectorising changes no rounding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "dsp/streaming_features.hpp"

namespace leakmon::dsp {

struct WindowFeature {
  std::uint64_t last_sample = 0;  // index (from 0, since construction or reset) of its last sample
  DetailFeature feature;
};

class BlockFeatures {
 public:
  static constexpr std::size_t kLanes = 8;  // windows computed together

  explicit BlockFeatures(const FeatureParams& params);  // allocates here only
  ~BlockFeatures();
  BlockFeatures(BlockFeatures&&) noexcept;
  BlockFeatures& operator=(BlockFeatures&&) noexcept;
  BlockFeatures(const BlockFeatures&) = delete;
  BlockFeatures& operator=(const BlockFeatures&) = delete;

  // Appends consecutive samples of the channel (any count, including a part of a window) and
  // calls sink(const WindowFeature&) once for every window they complete, in order, before
  // returning. Allocation-free; the sink runs between batches of at most kLanes windows.
  template <class Sink>
  void push_block(std::span<const double> samples, Sink&& sink) {
    while (!samples.empty()) {
      const std::size_t used = consume(samples);
      for (const WindowFeature& f : completed()) sink(f);
      samples = samples.subspan(used);
    }
  }

  std::uint64_t samples_seen() const noexcept;
  void reset() noexcept;  // forget history: the next sample is sample 0 again
  const FeatureParams& params() const noexcept;
  // True when windows are computed kLanes at a time from shared interior coefficients; false:
  // the step changes the decimation phase and every window is recomputed in full, one by one.
  bool incremental() const noexcept;

 private:
  // Takes samples until kLanes windows complete or the samples run out, computes the windows
  // completed, and returns how many samples it took (at least 1).
  std::size_t consume(std::span<const double> samples) noexcept;
  std::span<const WindowFeature> completed() const noexcept;

  struct Engine;
  Engine* engine_;
};

}  // namespace leakmon::dsp
