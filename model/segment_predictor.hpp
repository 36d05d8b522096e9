// "Simulating the model on the measured inputs" (docs/model-check.md): the plant integrates the
// valve flow into position, so a free open-loop run on the measured command drifts away for
// reasons that say nothing about the model. The record is therefore cut into short segments;
// each starts from the measured state (x, p1, p2 as read, v from a local fit of x, the spool
// from the exact zero-order-hold response to the measured u) and is simulated open loop on the
// measured u for its whole length. The same segment simulation serves fitting (least squares
// on the segment errors: multiple shooting) and scoring (NRMSE on held-out segments).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "model/actuator_model.hpp"
#include "model/measured_record.hpp"
#include "model/recent_results.hpp"
#include "sim/parameters.hpp"

namespace leakmon::model {

struct Segment {
  std::size_t begin = 0;
  std::size_t length = 0;
};

struct SegmentPlan {
  std::vector<Segment> fitting;   // the whole fitting part
  std::vector<Segment> held_out;  // data never used for fitting
};

struct SplitSettings {
  double block_s = 4.0;    // fitting and held-out blocks alternate with this length
  double segment_s = 0.5;  // length of one simulated segment
};

// Alternating blocks: a trend in the operating point cannot make the held-out part a different
// regime from the fitting part. Segments containing a gap are left out.
SegmentPlan split_record(const MeasuredRecord& record, const SplitSettings& settings = {});
// At most `count` segments, spread evenly over `segments` (to bound the cost of fitting).
std::vector<Segment> spread(std::span<const Segment> segments, std::size_t count);

// Predicted readings, record-sized; NaN outside the simulated segments.
struct Prediction {
  std::vector<double> x, p1, p2;
};

struct ChannelScales {
  double x = 1.0, p1 = 1.0, p2 = 1.0;
};

// The noise a correct model cannot predict (MODEL.md): the transducers' white noise per
// channel [m, Pa] and the spool flow noise (std. dev. as a fraction of travel, correlation
// time [s]).
struct NoiseLevels {
  double x = 0.0, p1 = 0.0, p2 = 0.0;
  double spool_sigma = 0.0, spool_tau = 1e-3;
};

// The fast part of the pressure difference p1 - p2 (mean square of its third differences on
// the floor's segments), in the capture and in the floor's draws: the spool flow noise rings
// the hydraulic mode there, far above what the steps excite.
struct FloorRinging {
  double measured = 0.0, drawn = 0.0;
};

class SegmentPredictor {
 public:
  explicit SegmentPredictor(const MeasuredRecord& record,
                            const sim::Parameters& rig = sim::Parameters::nominal());

  const MeasuredRecord& record() const { return record_; }
  const ChannelScales& scales() const { return scales_; }

  void predict(const ModelParameters& parameters, std::span<const Segment> segments,
               Prediction& out) const;
  // Number of residuals residuals() writes for these segments.
  static std::size_t residual_count(std::span<const Segment> segments);
  // Does `segment` reach `onset_s`, i.e. run any of its samples on the model from an onset
  // there (run() switches at the first sample at or after it)? One that does not has the
  // residuals of the model before the onset, whatever the effect that starts.
  bool reaches(const Segment& segment, double onset_s) const {
    return segment.length > 0 && record_.t[segment.begin + segment.length - 1] >= onset_s;
  }
  // (prediction - measurement) / channel scale for x, p1, p2 at every sample after each
  // segment's first; 0 where a sample is missing. Huge values when the model blows up.
  void residuals(const ModelParameters& parameters, std::span<const Segment> segments,
                 std::span<double> out) const;
  // FORMATS.md's nrmse: per channel RMS error over std of the measurement, averaged over x, p1,
  // p2, on the given segments.
  double nrmse(const ModelParameters& parameters, std::span<const Segment> segments) const;
  double nrmse(const Prediction& prediction, std::span<const Segment> segments) const;
  // The same per channel: x, p1, p2.
  std::array<double, 3> channel_nrmse(const Prediction& prediction,
                                      std::span<const Segment> segments) const;

  // The transducers' white-noise std. dev. per channel, read off the record: the robust
  // spread (median absolute value) of third differences, which white noise inflates by
  // sqrt(20) while the plant's smooth motion barely shows in them at 500 Hz. The spool flow
  // noise is the rig table's (it is not separable from the data at the sample level).
  NoiseLevels noise_levels() const;
  // The held-out NRMSE that the noise alone leaves (FORMATS.md `nrmse_floor`): `parameters`
  // simulated from a few samples before each segment's start with the spool flow noise drawn,
  // read through the transducer noise, against the same model's deterministic prediction from
  // the start read off those readings (the velocity fitted to them as to the capture), i.e.
  // what a correct model scores. Averaged over `repeats` draws. Per
  // channel (x, p1, p2); FORMATS.md's value is their mean, as for nrmse.
  // `pieces`: the spool flow noise is held over this many equal parts of each sample (an
  // exact Ornstein-Uhlenbeck draw at their spacing); 1 holds each sample's mean.
  std::array<double, 3> noise_floor(const ModelParameters& parameters,
                                    std::span<const Segment> segments, const NoiseLevels& noise,
                                    std::uint64_t seed, int repeats = 3, int pieces = 1,
                                    FloorRinging* ringing = nullptr) const;

 private:
  // `before`: the model up to onset_s, when an effect starts inside the capture.
  std::vector<double> spool_positions(const ActuatorModel& model,
                                      const ActuatorModel* before = nullptr,
                                      double onset_s = 0.0) const;
  // The same, kept for the last few spool laws: the spool runs over the whole record (its
  // state at a segment's start depends on all the commands before it), several times the
  // segments' own length, while a fit of the calibration or of most effects leaves the spool
  // law unchanged from one evaluation to the next.
  std::shared_ptr<const std::vector<double>> shared_spool_positions(
      const ActuatorModel& model, const ActuatorModel* before = nullptr,
      double onset_s = 0.0) const;
  template <typename Visit>
  void run(const ModelParameters& parameters, std::span<const Segment> segments,
           Visit&& visit) const;

  const MeasuredRecord& record_;
  sim::Parameters rig_;
  ChannelScales scales_;
  std::vector<double> velocity_;   // of x, model/piston_velocity.hpp
  std::vector<double> dp1_, dp2_;  // five-point slopes of the pressure readings
  // Everything spool_positions reads from its models (the spool's tau, u0 and u_max, then the
  // same before an onset and the onset's time; zeros without one): equal laws give equal
  // positions (compared bit for bit, recent_results.hpp).
  using SpoolLaw = std::array<double, 7>;
  static SpoolLaw spool_law(const ActuatorModel& model, const ActuatorModel* before,
                            double onset_s);
  // A handful: a fit alternates between at most a few laws (a model before and after an onset,
  // the floor's model between fits); more would only hold memory.
  mutable RecentResults<SpoolLaw, std::shared_ptr<const std::vector<double>>, 4> spool_runs_;
};

// Mean squared scaled residual of each segment.
std::vector<double> segment_errors(const SegmentPredictor& predictor,
                                   const ModelParameters& parameters,
                                   std::span<const Segment> segments);

// The error of `parameters` summed over `segments` with its onset moved to each of `onsets`
// [s] (an onset search). A segment that ends before an onset runs the model before it and one
// that starts `settle_s` or more after it the model after it (the spool's memory of the switch
// long gone), whatever the onset: those two runs are simulated once, and only the segments
// around each onset for it. Equal to simulating every segment for every onset to rounding.
std::vector<double> summed_errors_at_onsets(const SegmentPredictor& predictor,
                                            const ModelParameters& parameters,
                                            std::span<const Segment> segments,
                                            std::span<const double> onsets, double settle_s = 1.0);

}  // namespace leakmon::model
