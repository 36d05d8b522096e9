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
  std::vector<bool> valid;   // false where any of u, x, p1, p2 is a gap

  std::size_t size() const { return t.size(); }
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front() + dt; }
};

struct RecordRequirements {
  double min_duration_s = 20.0;
  double max_gap_fraction = 0.02;  // refuse when more samples than this are missing
  double rate_tolerance = 0.01;    // relative deviation of any t step from the period
};

// Reads and vets a capture file. Throws capture::CaptureError for malformed CSV (file:line:column)
// and ModelCheckError for data that cannot be diagnosed.
MeasuredRecord read_measured_record(const std::string& path, const RecordRequirements& req = {});
// The same checks on a capture already in memory (line numbers are then row numbers).
MeasuredRecord measured_record(const capture::Capture& capture, const RecordRequirements& req = {});

}  // namespace leakmon::model
