// A supply ripple is a spectral line (MODEL.md, last paragraph): a narrow peak standing far
// above its neighbourhood in the pressure spectrum, unlike the broad hydraulic resonance that
// the spool flow noise excites. Finding it first gives the ripple fit its frequency, which a
// local solver could never find on its own.
#pragma once

#include <optional>

#include "model/measured_record.hpp"

namespace leakmon::model {

struct SpectralLine {
  double frequency_hz = 0.0;
  double prominence = 0.0;  // peak power over the median power around it
};

struct LineSearch {
  double low_hz = 15.0;
  double high_hz = 220.0;
  double neighbourhood_hz = 3.0;
  // Low on purpose: the ripple fit and its held-out score decide; this only skips spectra
  // without any peak (a line of a few hundred kPa stands 25-100 times above its neighbours,
  // the tallest noise peak of a clean capture 10-20 times).
  double min_prominence = 8.0;
};

std::optional<SpectralLine> find_spectral_line(const MeasuredRecord& record,
                                               const LineSearch& search = {});

}  // namespace leakmon::model
