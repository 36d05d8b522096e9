// The plan of the incremental sliding-window transform, shared by StreamingFeatures (one window
// of many channels at a time) and BlockFeatures (many windows of one channel at a time): which
// coefficients of each level are "clean" (read no extended input and so are shared by
// consecutive windows), which edge values the boundary coefficients read, and how each
// extension value is obtained from those edges.
#pragma once

#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "dsp/detail_feature.hpp"
#include "dsp/dwt.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

// One level of the incremental scheme. At window start s (a multiple of 2^level), output k of
// this level equals the coefficient at absolute position (s >> level) + k of the transform of
// the unbounded stream whenever its taps read no extended input: that "clean" range
// [clean_lo, clean_hi) is computed once per position and kept in a RowHistory. Only the
// boundary outputs, which read the mode's extension, are recomputed per window, from copies of
// the input's two edges.
struct LevelPlan {
  Decimation dec;
  std::span<const double> filter;  // dec_lo below the feature level, dec_hi at it
  std::size_t clean_lo = 0;
  std::size_t clean_hi = 0;
  std::size_t edge_left = 0;   // input values a[0, edge_left) held for the left boundary
  std::size_t edge_right = 0;  // input values a[n_in - edge_right, n_in) for the right one
};

// One plan per level, or nothing when the step changes the decimation phase of some level or
// the window is too short for a clean interior (then every window is recomputed in full).
std::optional<std::vector<LevelPlan>> plan_incremental(const FeatureParams& params,
                                                       const Wavelet& w);

// One extension value of one edge buffer, resolved at construction so that the per-window work
// is a copy or a short formula over the lanes (channels, or windows): the same values, by the
// same arithmetic, as extend_before_start/extend_after_end (the streaming-equals-batch tests
// check every mode).
struct ExtensionSlot {
  enum class Kind { zero, copy, negate, smooth, antireflect } kind = Kind::zero;
  double* dst = nullptr;
  const double* a = nullptr;  // copy/negate: source; smooth/antireflect: the edge value
  const double* b = nullptr;  // smooth: the value next to the edge; antireflect: the mirrored one
  double factor = 0.0;        // smooth: distance from the edge

  void fill(std::size_t lanes) const noexcept {
    switch (kind) {
      case Kind::zero:
        for (std::size_t c = 0; c < lanes; ++c) dst[c] = 0.0;
        break;
      case Kind::copy:
        for (std::size_t c = 0; c < lanes; ++c) dst[c] = a[c];
        break;
      case Kind::negate:
        for (std::size_t c = 0; c < lanes; ++c) dst[c] = -a[c];
        break;
      case Kind::smooth:
        for (std::size_t c = 0; c < lanes; ++c) dst[c] = a[c] + factor * (a[c] - b[c]);
        break;
      case Kind::antireflect:
        for (std::size_t c = 0; c < lanes; ++c) dst[c] = a[c] - (b[c] - a[c]);
        break;
    }
  }
};

// Appends to `slots` every extension value of one level's edge buffers, which hold `lanes`
// interleaved values per row: left_real points at the row of a[0] (the left_ext extension rows
// precede it), right_real at the row of a[n_in - edge_right] (the right_ext rows follow the
// edge_right real ones). The plan guarantees a single reflection, so every value reads the
// edges' real rows.
void append_extension_slots(const LevelPlan& level, Mode mode, double* left_real,
                            double* right_real, std::size_t lanes,
                            std::vector<ExtensionSlot>& slots);

inline DetailFeature feature_from_energy(double energy, std::size_t count) noexcept {
  return {std::sqrt(energy / static_cast<double>(count)), energy, true};
}

}  // namespace leakmon::dsp
