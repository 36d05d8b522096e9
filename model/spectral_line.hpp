// A supply ripple is a spectral line (MODEL.md, last paragraph) locked to absolute time:
// ps(t) = ps0 + dP sin(2 pi f t). It reaches the chambers through the valve's null leakage and
// any open land, and it raises or lowers both chambers together, so it shows best in p1 + p2
// (or in `ps` itself when the capture has it): the spool flow noise and the piston's motion
// move p1 and p2 in opposite directions and largely cancel there. Finding the line first also
// gives the ripple fit its frequency, which a local solver could never find on its own.
//
// The test is a held-out coherent demodulation. The first half of the capture alone picks
// candidate frequencies (its most prominent narrow peaks) and the line's phase at each; the
// second half is then demodulated at each candidate and projected on that phase. With the
// frequency and phase fixed by data the second half never saw, each projection is, without a
// line, a zero-mean Gaussian whose variance the held-out spectrum at neighbouring frequencies
// gives: a plain z statistic, free of the selection bias of a peak searched on the same data.
// `held_out_z` is the largest of the `candidates` statistics, so without a line
// P(held_out_z > c) <= candidates * Q(c) (8 * 3.4e-6 at the naming threshold 4.5). Several
// candidates, not one: a weak ripple on a 30 s capture is only about as prominent in one half
// as the tallest of its ~3000 noise bins (prominence 12.7 against a noise peak's 13.7 seen),
// yet clear when tested alone (z 5.8). A real ripple keeps its phase over the whole capture;
// oscillations that restart with every step (a limit cycle, say) do not, and average out.
#pragma once

#include <optional>

#include "model/measured_record.hpp"

namespace leakmon::model {

struct SpectralLine {
  double frequency_hz = 0.0;
  double prominence = 0.0;          // first half: peak power over the median power around it
  double held_out_z = 0.0;          // largest candidate's coherent second-half statistic
  bool from_supply_column = false;  // tested on the capture's `ps`, not on p1 + p2
};

struct LineSearch {
  double low_hz = 15.0;
  double high_hz = 220.0;
  double neighbourhood_hz = 3.0;  // for the prominence's median
  // Held-out noise level: the spectrum between these offsets on either side of the line.
  double noise_offset_low_hz = 1.0;
  double noise_offset_high_hz = 5.0;
  double noise_step_hz = 0.1;
  std::size_t candidates = 8;  // first-half peaks tested on the second half
};

// The most prominent line of the first half and its test on the second half.
std::optional<SpectralLine> find_spectral_line(const MeasuredRecord& record,
                                               const LineSearch& search = {});

}  // namespace leakmon::model
