// A leak that opens while a detector learns is learned as healthy: from then on the detector
// judges the leaky rig against itself and stays silent. This probe looks at the learning period
// once it is over, with the feature the detector learned (the flow balance's at-rest command
// residual against the load; the d2 index for the pressure-only detectors): a reference from the
// first kReferenceShare of it, then the rest searched for one step of alarm-worthy size that
// stays. It cannot undo the learning (nothing healthy is left to learn from); it makes it
// visible, so that an operator relearns on a rig known to be tight.
//
// What is alarm-worthy: for the flow balance an added leak slope of at least the detector's
// min_leak (and design_leak); for the index a drop of the block mean beyond the reference's
// spread and by a share no healthy drift gives in a learning period (MODEL.md "Drifting
// operating conditions": warm-ups, cooler cycles and supply changes move the index slowly and by
// less). docs/detection.md "A leak during learning" has the rates measured.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace leakmon::detect {

// The share of the learning period, from its start, that serves as the reference.
inline constexpr double kReferenceShare = 0.4;
// Residual degrees of freedom a reference needs to estimate its own spread.
inline constexpr std::size_t kMinReferenceDof = 4;

struct LearnedChange {
  double change_t = 0.0;     // estimated source time of the step [s]
  std::string_view feature;  // "command_residual" (flow balance) or "index"
  std::string_view channel;  // "u" for the command residual; "p1" or "p2" for the index
  // Command residual: the added leak coefficient [m^3/(s Pa)] (at 40 degC with a temperature).
  // Index: the drop of the index [Pa] from the reference level.
  double size = 0.0;
  double reference = 0.0;  // index: the reference level [Pa]; command residual: 0
  double z = 0.0;          // the step in units of its standard error
};

// One block of the flow balance's at-rest hops: the mean command residual against the healthy
// relation fitted to the reference share, and the mean leak term (MODEL.md: the opening a leak
// needs per unit of its coefficient).
struct ResidualBlock {
  double t_first = 0.0;  // times of the block's first and last hops [s]
  double t = 0.0;
  double residual = 0.0;
  double leak_term = 0.0;
};

struct SlopeStepOptions {
  // The smallest added slope (in the residual's units per unit leak term) that is alarm-worthy.
  double floor_slope = 0.0;
  // The slope's value in m^3/(s Pa) per unit, to state the size as a leak coefficient.
  double slope_to_coefficient = 1.0;
  // The step's significance needed: the scan takes the best of many change times, and blocks
  // of one hold are correlated, so well above a single test's.
  double min_z = 6.0;
  std::size_t min_blocks_after = 4;  // a step must hold for this many blocks
  // Terms of the healthy relation fitted to the reference blocks: they take that many degrees of
  // freedom from the reference's spread, and a reference with fewer than kMinReferenceDof left
  // cannot say what a step's significance is.
  std::size_t fitted_terms = 0;
  // The residual's name in the event: the at-rest balance's command or flow_law's flow.
  std::string_view feature = "command_residual";
};

// blocks: in time order, the first `reference_blocks` of them the reference share (whose
// residuals the healthy relation was fitted to). The step (a positive added slope: a leak needs
// more opening towards the loaded chamber) found at the block that explains the rest best, when
// it is alarm-worthy.
std::optional<LearnedChange> find_slope_step(std::span<const ResidualBlock> blocks,
                                             std::size_t reference_blocks,
                                             const SlopeStepOptions& options);

// The index probe: fed every learning hop's index of one chamber, judged once when learning
// ends. Block means over block_seconds average out the test program's excitation; the memory is
// reserved when it is built (the worker thread allocates nothing per hop).
class IndexStepProbe {
 public:
  struct Options {
    double block_seconds = 4.0;
    // A step needs its mean below the reference's median by this many reference spreads (the
    // spread of block means, robust), and below the reference's lowest block...
    double min_spreads = 4.0;
    // ...and by at least this share of the reference level: the leaks of interest damp the
    // hydraulic mode by far more, healthy drift within a learning period by less.
    double min_relative_drop = 0.25;
    std::size_t min_blocks_after = 3;
    // The share of blocks after the step that must lie below the reference's lowest block.
    double min_share_below = 0.7;
  };

  IndexStepProbe(std::string_view channel, double learning_seconds, double hop_seconds,
                 const Options& options);
  IndexStepProbe(std::string_view channel, double learning_seconds, double hop_seconds)
      : IndexStepProbe(channel, learning_seconds, hop_seconds, Options{}) {}

  // One learning hop: its time and index [Pa] (NaN: not counted).
  void add(double t, double index);
  // Once learning is over: the step, when there is one of alarm-worthy size.
  std::optional<LearnedChange> judge() const;
  void clear();

 private:
  struct Block {
    double t_first = 0.0, t = 0.0;  // times of its first and last hops
    double mean = 0.0;
  };
  void close_block();

  std::string_view channel_;
  Options options_;
  std::size_t block_hops_;
  std::vector<Block> blocks_;            // reserved for the learning period and some slack
  mutable std::vector<double> scratch_;  // as many: the reference's block means, for medians
  double sum_ = 0.0, first_t_ = 0.0, last_t_ = 0.0;
  std::size_t count_ = 0, hops_in_block_ = 0;
};

}  // namespace leakmon::detect
