// Where an effect starts inside a capture (issue 24, FORMATS.md `onset_s`): a leak opening, a
// friction changing or a transducer shifting at t0 makes the calibrated nominal model's error
// step up at t0 and stay up, where a constant effect's error follows the operating point over
// the whole capture and a drifting condition (the oil warming) grows it gradually. The
// proposal is the split of the capture's segments, in time order, that separates the per-
// segment log errors best (Welch t of later minus earlier); the model check then fits the
// effects with that onset and lets held-out data decide between them and the constant ones.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "model/segment_predictor.hpp"

namespace leakmon::model {

struct ChangePoint {
  std::size_t index = 0;   // first segment after the change (in the time-ordered list)
  double t_s = 0.0;        // capture time of that segment's start [s]
  double statistic = 0.0;  // Welch t of the later segments' mean log error over the earlier's
  double step = 0.0;       // the two means' difference (natural log of the error ratio)
};

// Every segment of a plan (fitting and held-out), in time order.
std::vector<Segment> segments_in_time_order(const SegmentPlan& plan);

// The indices of `segments` in which the piston moves: its position's range over the segment
// is at least `share` of the 90th percentile of the segments' ranges (a step's transient, not
// a hold's small corrections). An effect that shows only in motion (a slower spool, a dead
// band, a supply droop) leaves the error of every hold as it was, and the holds, whose errors
// follow the operating point, hide its onset in a split of all segments.
std::vector<std::size_t> moving_segments(const MeasuredRecord& record,
                                         std::span<const Segment> segments, double share = 0.25);

// `log_errors[i]`: the log mean squared error of `segments[i]` (time order). Splits leave at
// least `min_side` segments on either side. nullopt when there are too few segments.
std::optional<ChangePoint> find_change_point(const MeasuredRecord& record,
                                             std::span<const Segment> segments,
                                             std::span<const double> log_errors,
                                             std::size_t min_side = 8);

// How much each segment excites the rig, as regressors of its error: the log of the position's
// range (a hold's against a stroke) and of its rms sample-to-sample change (the same range
// swept faster). Both from x, the one channel every capture has.
std::vector<std::vector<double>> segment_excitation(const MeasuredRecord& record,
                                                    std::span<const Segment> segments);

// The split of `log_errors` with the excitation regressed out jointly: for each split j,
// log_errors[i] = a + sum_k b_k excitation[k][i] + c [i >= j], and the split's statistic is
// c's t. A test program's phases move the error with their excitation (a hold's is the
// transducers' noise, a sweep's end its fastest motion) far more than an effect's onset does,
// and the plain split lands at the phase change; an onset inside a phase is a step the
// excitation does not explain (818208: a sensor lag from 84.5 s in a sine block, every plain
// split at a sweep's fast end 175.5 s, this one at 84.5 s). `step` is c.
std::optional<ChangePoint> find_change_point_beyond_excitation(
    const MeasuredRecord& record, std::span<const Segment> segments,
    std::span<const double> log_errors, const std::vector<std::vector<double>>& excitation,
    std::size_t min_side = 8);

}  // namespace leakmon::model
