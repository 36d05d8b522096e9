// One hop of a capture as the daemon's worker hands it to a detector: the hop's means of every
// acquired signal, and the per-sample spans of u, x, p1 and p2 (flow_law integrates them).
#pragma once

#include <cstddef>
#include <vector>

#include "capture/capture.hpp"
#include "detect/detector.hpp"

namespace leakmon::test {

// The hop of `samples` rows from `start`; `ps` and `temp` where the capture records them. The
// spans point into `capture`, which must outlive the observation.
inline detect::Observation hop_observation(const capture::Capture& capture, std::size_t start,
                                           std::size_t samples) {
  const auto mean = [&](const std::vector<double>& column) {
    double sum = 0.0;
    for (std::size_t i = start; i < start + samples; ++i) sum += column[i];
    return sum / static_cast<double>(samples);
  };
  const auto& u = capture.column("u");
  const auto& x = capture.column("x");
  const auto& p1 = capture.column("p1");
  const auto& p2 = capture.column("p2");
  detect::Observation o;
  o.t = capture.column("t")[start + samples - 1];
  o.u = mean(u);
  o.x = mean(x);
  o.p1 = mean(p1);
  o.p2 = mean(p2);
  if (capture.has("ps")) o.ps = mean(capture.column("ps"));
  if (capture.has("temp")) o.temp = mean(capture.column("temp"));
  o.u_samples = {u.data() + start, samples};
  o.x_samples = {x.data() + start, samples};
  o.p1_samples = {p1.data() + start, samples};
  o.p2_samples = {p2.data() + start, samples};
  return o;
}

}  // namespace leakmon::test
