#include "dsp/incremental_plan.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dsp/extension.hpp"

namespace leakmon::dsp {

std::optional<std::vector<LevelPlan>> plan_incremental(const FeatureParams& params,
                                                       const Wavelet& w) {
  const std::size_t taps = w.filter_length();
  const std::size_t decimation_period = std::size_t{1} << params.level;
  if (params.step % decimation_period != 0) return std::nullopt;  // phase would change
  std::vector<LevelPlan> plan;
  std::size_t n_in = params.window;
  std::size_t prev_lo = 0;
  std::size_t prev_hi = params.window;
  for (int level = 1; level <= params.level; ++level) {
    LevelPlan p;
    p.dec = decimation(n_in, taps, params.mode);
    p.filter = level < params.level ? w.dec_lo : w.dec_hi;
    if (n_in < taps) return std::nullopt;  // extension would reflect more than once
    const auto phase = static_cast<long long>(p.dec.phase);
    const long long lowest = static_cast<long long>(prev_lo + taps - 1) - phase;
    p.clean_lo = lowest <= 0 ? 0 : static_cast<std::size_t>((lowest + 1) / 2);
    const long long highest = static_cast<long long>(prev_hi) - 1 - phase;
    if (highest < 0) return std::nullopt;
    p.clean_hi = std::min(p.dec.n_out, static_cast<std::size_t>(highest / 2 + 1));
    if (p.clean_lo >= p.clean_hi) return std::nullopt;
    const std::size_t left_reads = p.clean_lo == 0 ? 0 : 2 * (p.clean_lo - 1) + p.dec.phase + 1;
    const long long first_right_read =
        static_cast<long long>(2 * p.clean_hi + p.dec.phase) - static_cast<long long>(taps - 1);
    const std::size_t right_reads =
        first_right_read >= static_cast<long long>(n_in)
            ? 0
            : n_in - static_cast<std::size_t>(std::max(0LL, first_right_read));
    p.edge_left = std::max(taps, left_reads);
    p.edge_right = std::max(taps, right_reads);
    if (p.edge_left > prev_hi || p.edge_right > n_in - prev_lo || p.edge_left > n_in ||
        p.edge_right > n_in) {
      return std::nullopt;
    }
    plan.push_back(p);
    prev_lo = p.clean_lo;
    prev_hi = p.clean_hi;
    n_in = p.dec.n_out;
  }
  return plan;
}

void append_extension_slots(const LevelPlan& l, Mode mode, double* left_real, double* right_real,
                            std::size_t lanes, std::vector<ExtensionSlot>& slots) {
  const std::size_t n = l.dec.n_in;
  const std::size_t right_first = n - l.edge_right;
  auto row = [&](std::size_t i) -> const double* {
    if (i < l.edge_left) return left_real + i * lanes;
    if (i < right_first) throw std::logic_error("extension reads outside the edge buffers");
    return right_real + (i - right_first) * lanes;
  };
  // For the modes that only pick (and maybe negate) a sample, probe which one: a[i] = i + 1.
  auto probe = [](std::size_t i) { return static_cast<double>(i) + 1.0; };
  auto slot = [&](double* dst, std::size_t m, bool left) {
    ExtensionSlot e;
    e.dst = dst;
    const std::size_t edge = left ? 0 : n - 1;
    const std::size_t inward = left ? edge + 1 : edge - 1;
    switch (mode) {
      case Mode::zero:
        break;
      case Mode::smooth:
        e = {ExtensionSlot::Kind::smooth, dst, row(edge), row(inward), static_cast<double>(m)};
        break;
      case Mode::antireflect:
        e = {ExtensionSlot::Kind::antireflect, dst, row(edge), row(left ? edge + m : edge - m),
             0.0};
        break;
      default: {
        const double v =
            left ? extend_before_start(mode, n, m, probe) : extend_after_end(mode, n, m, probe);
        e.kind = v < 0 ? ExtensionSlot::Kind::negate : ExtensionSlot::Kind::copy;
        e.a = row(static_cast<std::size_t>(std::abs(v)) - 1);
      }
    }
    slots.push_back(e);
  };
  for (std::size_t m = 1; m <= l.dec.left_ext; ++m) slot(left_real - m * lanes, m, true);
  for (std::size_t m = 1; m <= l.dec.right_ext; ++m) {
    slot(right_real + (l.edge_right - 1 + m) * lanes, m, false);
  }
}

}  // namespace leakmon::dsp
