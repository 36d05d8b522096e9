// Sliding-window wavelet detail features (the leakage index of Goharrizi, Sepehri and Wu):
// per window, the RMS and energy of the level-`level` detail coefficients of
// pywt.wavedec(window, wavelet, mode, level). Batch and streaming forms give identical values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dsp/detail_feature.hpp"
#include "dsp/mode.hpp"

namespace leakmon::dsp {

class StreamingFeatures {
 public:
  StreamingFeatures(const FeatureParams& params, std::size_t channels);  // allocates here only
  ~StreamingFeatures();
  StreamingFeatures(StreamingFeatures&&) noexcept;
  StreamingFeatures& operator=(StreamingFeatures&&) noexcept;
  StreamingFeatures(const StreamingFeatures&) = delete;
  StreamingFeatures& operator=(const StreamingFeatures&) = delete;

  // One multi-channel sample (size == channels). Returns true when it completes a window; then
  // latest() holds one DetailFeature per channel. noexcept, allocation-free.
  bool push(std::span<const double> sample) noexcept;
  std::span<const DetailFeature> latest() const noexcept;
  std::uint64_t samples_seen() const noexcept;
  void reset() noexcept;  // forget history (e.g. after a reload)
  const FeatureParams& params() const noexcept;
  std::size_t channels() const noexcept;
  // True when updates reuse the previous window's interior coefficients (the step keeps the
  // decimation phase of every level); false: each window is recomputed in full.
  bool incremental() const noexcept;

 private:
  struct Engine;
  Engine* engine_;
};

// Batch: one value per window (first window = samples 0..window-1, then every `step`).
std::vector<DetailFeature> sliding_detail_features(std::span<const double> signal,
                                                   const FeatureParams& params);

}  // namespace leakmon::dsp
