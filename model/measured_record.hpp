// The measured signals the model check works on, read and vetted from a capture (FORMATS.md):
// t, u, x, p1, p2 at a regular rate, long enough and with few enough gaps to split into fitting
// and held-out parts. Anything else is refused with a reason naming the file (and line/column
// where a single sample is at fault).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "capture/capture.hpp"

namespace leakmon::model {

class ModelCheckError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MeasuredRecord {
  std::string source;      // file the data came from
  std::string controller;  // "basic", "fault_tolerant" or "" when the capture does not say
  double dt = 0.002;       // sample period [s]
  std::vector<double> t, u, x, p1, p2;
  std::vector<double> xref;  // empty when the capture has none
  std::vector<double> ps;    // supply pressure; empty when the capture has none
  std::vector<double> temp;  // oil temperature [degC]; empty when the capture has none
  std::vector<bool> valid;   // false where any of u, x, p1, p2 is a gap or censored
  // Readings a transducer fault or its range made meaningless, left out like gaps (an isolated
  // spike is instead replaced by its neighbours' median, which keeps the segment): a pressure
  // clipped at the top of its range says only "at least this much", and the model knows no
  // range; a value held exactly for a long run (frozen, dropped out to 0, saturated) is not a
  // measurement at all (MODEL.md "Sensor faults": at rest a reading still moves by an LSB).
  struct Censored {
    enum class Reason { range_end, held, spikes };
    Reason reason = Reason::range_end;
    std::string channel;  // "x", "p1" or "p2"
    // The reading it sticks at (range_end), the first run's (held), the largest jump (spikes).
    double value = 0.0;
    std::size_t samples = 0;  // samples left out (spikes: replaced by their neighbours' median)
    std::size_t runs = 0;     // held: how many runs
    std::string first;        // where the first one is (file line or row)
    double held_min_s = 0.0;  // held: the run length that counted as held [s]
  };
  std::vector<Censored> censored;

  std::size_t size() const { return t.size(); }
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front() + dt; }
};

struct RecordRequirements {
  double min_duration_s = 20.0;
  double max_gap_fraction = 0.02;  // refuse when more samples than this are missing
  // A pressure's largest reading counts as its range end when it repeats at least
  // `pinned_min_samples` times and `pinned_ratio` times as often as the next one below it: a
  // pressure moving past a clip piles up there, one cresting near its top (a slow sine's
  // crest reads its top code about twice as often as its neighbours) does not.
  std::size_t pinned_min_samples = 10;
  double pinned_ratio = 4.0;
  // One exact value repeated for this long is held, not measured: with the noise of about one
  // LSB that MODEL.md's transducers show at rest, a healthy run of even 50 samples has odds
  // below 1e-10.
  double held_min_s = 0.25;
  // An isolated sample off its four neighbours' median by `spike_scales` robust scales of the
  // channel's deviations and by `spike_spread` times their own spread is a spike (MODEL.md:
  // off by MPa, a few per minute); a channel with more than `max_spikes_per_min` such samples
  // is moving that way (a rig hunting at its mode), and keeps them.
  double spike_scales = 12.0;
  double spike_spread = 4.0;
  double max_spikes_per_min = 30.0;
  // Refuse a capture with more of its samples censored than this: too much of it is a fault.
  double max_censored_fraction = 0.25;
  double rate_tolerance = 0.01;  // relative deviation of any t step from the period
};

// Reads and vets a capture file. Throws capture::CaptureError for malformed CSV (file:line:column)
// and ModelCheckError for data that cannot be diagnosed.
MeasuredRecord read_measured_record(const std::string& path, const RecordRequirements& req = {});
// The same checks on a capture already in memory (line numbers are then row numbers).
MeasuredRecord measured_record(const capture::Capture& capture, const RecordRequirements& req = {});

}  // namespace leakmon::model
