// The healthy reference a block's residual is judged against while the rig drifts slowly (the
// oil warming or cooling, MODEL.md "Drifting operating conditions"): a line in time fitted to
// the residuals of the healthy blocks in a window that ends `guard_seconds` ago, extrapolated
// to now. A leak opens within a second or so and is judged long before it reaches the window,
// while a drift of a few percent an hour is followed; blocks are left out of it while the
// CUSUM is suspicious (the caller does not add() them), so a leak is never learned as drift.
//
// A block is (t, residual, scale) with residual = scale (a + b (t - now)): the reference is a
// level per unit of the block's scale (flow_balance: the leak term, so the reference is a
// slope on it; the feature test: 1), fitted by least squares weighted by scale^2. The two
// detectors' references differ in a few rules, which are options here.
#pragma once

#include <cstddef>
#include <string_view>

#include "detect/detector_state.hpp"
#include "detect/ring.hpp"

namespace leakmon::detect {

struct DriftReferenceOptions {
  double guard_seconds = 60.0;
  // The window's length; 0 switches following off (the reference is then 0, except the level
  // of the blocks after a re-anchoring, see reference()).
  double window_seconds = 240.0;
  // How long blocks are kept: guard, window and any re-anchoring time, plus one block.
  double keep_seconds = 301.0;
  double block_seconds = 0.8;
  // The extrapolation from the window's level to now is bounded by this (in the reference's
  // units), so a trend fitted to a few noisy blocks never carries it further than a leak.
  double bound = 0.0;
  // The slope is shrunk by b^2 / (b^2 + var b): followed where the window identifies it, its
  // noise is not (with the default window its noise extrapolated over the guard is about the
  // designed drop). Without, the fitted line's value at now is used as it is.
  bool shrink_slope = false;
  // A slope needs blocks spanning 0.9 of the window (after a re-anchoring the window refills;
  // over a shorter span the slope's noise, extrapolated over the guard, exceeds the drift).
  bool slope_needs_full_window = false;
  // When the newest block in the window is older than the guard again (the blocks stopped: a
  // program the caller does not judge, a stretch under suspicion), the window ends at that
  // block and the line is carried a guard beyond it, no further: the reference holds what the
  // blocks said when they stopped. Without, the window slides on and its level is that of
  // fewer and fewer old blocks (a feature test's reference wandered by 1.5 block spreads
  // within a minute of a sine that followed the steps, judging the sine by it). With it, the
  // full window a slope needs is the blocks' own span, not the window's: the window had held
  // only the 100 s of steps before a three-minute triangle, and their slope was carried 230 s
  // on to now (a false alarm 38 s into the steps that followed).
  bool hold_across_gaps = false;
};

class DriftReference {
 public:
  // Blocks in the window before it gives a level, and before it fits a slope.
  static constexpr std::size_t kLevelBlocks = 3;
  static constexpr std::size_t kSlopeBlocks = 20;

  explicit DriftReference(const DriftReferenceOptions& options);

  // A healthy block that ended at t.
  void add(double t, double residual, double scale = 1.0) { blocks_.push({t, residual, scale}); }
  // Forget every block: the residuals before belong to another supply (a re-anchoring), or to
  // another clock (a restart after a gap).
  void clear() { blocks_.clear(); }
  // A state of a build before hold_across_gaps decides as that build did.
  void set_hold_across_gaps(bool hold) { options_.hold_across_gaps = hold; }
  bool holds_across_gaps() const { return options_.hold_across_gaps; }

  // The reference at t: 0 with fewer than kLevelBlocks in the window, their level with fewer
  // than kSlopeBlocks or when `level_only`, else the line extrapolated to t. `block_sigma`:
  // the spread of a block's residual (for the shrinkage). `anchored_until`: after a
  // re-anchoring, the window reaches up to this time, later than the guard (the blocks since
  // the step are all the reference there is); NaN when none.
  double reference(double t, double block_sigma, bool level_only, double anchored_until) const;

  // `prefix.{t,residual,scale,next}`.
  void save(DetectorState& state, std::string_view prefix) const;
  void restore(const DetectorState& state, std::string_view prefix);

 private:
  struct Block {
    double t, residual, scale;
  };
  static constexpr std::array<RecordField<Block>, 3> kBlockFields = {
      record_field<&Block::t>("t"), record_field<&Block::residual>("residual"),
      record_field<&Block::scale>("scale")};

  DriftReferenceOptions options_;
  Ring<Block> blocks_;
};

}  // namespace leakmon::detect
