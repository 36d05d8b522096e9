#include "model/misfit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace leakmon::model {
namespace {

constexpr const char* kChannels[3] = {"x", "p1", "p2"};
constexpr int kRateHalfWindow = 5;  // residual rate over +-10 ms: the error's growth, less noise
constexpr int kLocalHalfWindow = 3;

struct Moments {
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  void add(double x, double y) {
    n += 1;
    sx += x;
    sy += y;
    sxx += x * x;
    syy += y * y;
    sxy += x * y;
  }
  double correlation() const {
    if (n < 3) return 0.0;
    const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n;
    if (vx <= 0.0 || vy <= 0.0) return 0.0;
    return (sxy - sx * sy / n) / std::sqrt(vx * vy);
  }
};

double welch_t(const std::vector<double>& a, const std::vector<double>& b) {
  const auto stats = [](const std::vector<double>& v) {
    double m = 0.0;
    for (double x : v) m += x;
    m /= static_cast<double>(v.size());
    double s = 0.0;
    for (double x : v) s += (x - m) * (x - m);
    return std::pair{m, s / std::max(1.0, static_cast<double>(v.size()) - 1.0)};
  };
  if (a.size() < 2 || b.size() < 2) return 0.0;
  const auto [ma, va] = stats(a);
  const auto [mb, vb] = stats(b);
  const double se =
      std::sqrt(va / static_cast<double>(a.size()) + vb / static_cast<double>(b.size()));
  return se > 0.0 ? (mb - ma) / se : 0.0;
}

}  // namespace

Misfit locate_misfit(const SegmentPredictor& predictor, const ModelParameters& parameters,
                     std::span<const Segment> segments, const std::array<double, 3>& floor) {
  Misfit m;
  const MeasuredRecord& rec = predictor.record();
  Prediction pred;
  predictor.predict(parameters, segments, pred);
  m.channel_nrmse = predictor.channel_nrmse(pred, segments);
  m.channel_floor = floor;
  // The channel furthest above its floor (squared excess: noise adds in power).
  std::size_t worst = 0;
  double worst_excess = -1.0;
  for (std::size_t c = 0; c < 3; ++c) {
    const double excess = m.channel_nrmse[c] * m.channel_nrmse[c] - floor[c] * floor[c];
    if (excess > worst_excess) {
      worst_excess = excess;
      worst = c;
    }
  }
  m.channel = kChannels[worst];
  const std::vector<double>* measured[3] = {&rec.x, &rec.p1, &rec.p2};
  const std::vector<double>* predicted[3] = {&pred.x, &pred.p1, &pred.p2};
  const auto& y = *measured[worst];
  const auto& yp = *predicted[worst];
  const auto residual = [&](std::size_t k) { return yp[k] - y[k]; };

  double u_peak = 0.0;
  for (std::size_t k = 0; k < rec.size(); ++k) {
    if (std::isfinite(rec.u[k])) u_peak = std::max(u_peak, std::abs(rec.u[k]));
  }
  const double dt = rec.dt;
  const char* names[] = {"load_pressure", "velocity",      "velocity_sign", "dp_dt",
                         "du_dt",         "small_command", "flow",          "time"};
  constexpr std::size_t kRegressors = std::size(names);
  Moments moments[kRegressors];
  for (const auto& seg : segments) {
    const std::size_t lo = seg.begin + 1 + kRateHalfWindow;
    const std::size_t hi = seg.begin + seg.length - kRateHalfWindow;
    for (std::size_t k = lo; k < hi; ++k) {
      if (k < kLocalHalfWindow || k + kLocalHalfWindow >= rec.size()) continue;
      const double rate = (residual(k + kRateHalfWindow) - residual(k - kRateHalfWindow)) /
                          (2.0 * kRateHalfWindow * dt);
      if (!std::isfinite(rate)) continue;
      const double v = (rec.x[k + kLocalHalfWindow] - rec.x[k - kLocalHalfWindow]) /
                       (2.0 * kLocalHalfWindow * dt);
      const double load = rec.p1[k] - rec.p2[k];
      const double load_rate = (rec.p1[k + kLocalHalfWindow] - rec.p2[k + kLocalHalfWindow] -
                                rec.p1[k - kLocalHalfWindow] + rec.p2[k - kLocalHalfWindow]) /
                               (2.0 * kLocalHalfWindow * dt);
      const double du = (rec.u[k + 1] - rec.u[k - 1]) / (2.0 * dt);
      const double values[kRegressors] = {
          load, v, v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0), load_rate, du,
          std::abs(rec.u[k]) < 0.05 * u_peak ? 1.0 : 0.0,
          // The valve's flow grows with the opening (the command) and with the square root
          // of the pressure drop across it; the opening is what the capture shows directly.
          std::abs(rec.u[k]), rec.t[k]};
      for (std::size_t i = 0; i < kRegressors; ++i) {
        if (std::isfinite(values[i])) moments[i].add(values[i], rate);
      }
    }
  }
  for (std::size_t i = 0; i < kRegressors; ++i) {
    m.regressors.push_back({names[i], moments[i].correlation()});
  }
  std::stable_sort(m.regressors.begin(), m.regressors.end(), [](const auto& a, const auto& b) {
    return std::abs(a.correlation) > std::abs(b.correlation);
  });

  // Residual power per DFT bin of each segment; white noise is flat, estimated from the top
  // of the band (100-250 Hz), and only the power above it counts.
  const double edges[] = {0.0, 2.0, 10.0, 50.0, 1.0 / (2.0 * dt) + 1e-9};
  constexpr std::size_t kBands = std::size(edges) - 1;
  double band_power[kBands] = {};
  std::vector<double> high_bins;
  std::vector<std::pair<double, double>> bins;  // (frequency, power)
  for (const auto& seg : segments) {
    const std::size_t n = seg.length - 1;
    std::vector<double> r(n);
    bool finite = true;
    for (std::size_t j = 0; j < n; ++j) {
      r[j] = residual(seg.begin + 1 + j);
      finite = finite && std::isfinite(r[j]);
    }
    if (!finite) continue;
    for (std::size_t f = 0; f <= n / 2; ++f) {
      std::complex<double> sum = 0.0;
      const double w = -2.0 * std::numbers::pi * static_cast<double>(f) / static_cast<double>(n);
      for (std::size_t j = 0; j < n; ++j) sum += r[j] * std::polar(1.0, w * static_cast<double>(j));
      const double power = std::norm(sum) / static_cast<double>(n);
      const double hz = static_cast<double>(f) / (static_cast<double>(n) * dt);
      bins.emplace_back(hz, power);
      if (hz >= 100.0) high_bins.push_back(power);
    }
  }
  double white = 0.0;
  if (!high_bins.empty()) {
    auto mid = high_bins.begin() + static_cast<std::ptrdiff_t>(high_bins.size() / 2);
    std::nth_element(high_bins.begin(), mid, high_bins.end());
    white = *mid / std::log(2.0);  // median of an exponential is its mean ln 2
  }
  double total = 0.0;
  for (const auto& [hz, power] : bins) {
    const double excess = std::max(power - white, 0.0);
    for (std::size_t b = 0; b < kBands; ++b) {
      if (hz >= edges[b] && hz < edges[b + 1]) band_power[b] += excess;
    }
    total += excess;
  }
  std::size_t best_band = 0;
  for (std::size_t b = 1; b < kBands; ++b) {
    if (band_power[b] > band_power[best_band]) best_band = b;
  }
  m.band_low_hz = edges[best_band];
  m.band_high_hz = std::min(edges[best_band + 1], 1.0 / (2.0 * dt));
  m.band_share = total > 0.0 ? band_power[best_band] / total : 0.0;

  // Early against late: per-segment log squared error (all channels, scaled).
  const double t0 = rec.t.front(), span = rec.duration();
  std::vector<double> early, late;
  const auto& scales = predictor.scales();
  const double scale[3] = {scales.x, scales.p1, scales.p2};
  for (const auto& seg : segments) {
    double sum = 0.0;
    std::size_t n = 0;
    for (std::size_t k = seg.begin + 1; k < seg.begin + seg.length; ++k) {
      for (std::size_t c = 0; c < 3; ++c) {
        const double e = ((*predicted[c])[k] - (*measured[c])[k]) / scale[c];
        if (std::isfinite(e)) {
          sum += e * e;
          ++n;
        }
      }
    }
    if (n == 0) continue;
    const double position = (rec.t[seg.begin] - t0) / span;
    const double value = std::log(std::max(sum / static_cast<double>(n), 1e-300));
    if (position < 1.0 / 3.0) early.push_back(value);
    if (position >= 2.0 / 3.0) late.push_back(value);
  }
  if (!early.empty() && !late.empty()) {
    double me = 0.0, ml = 0.0;
    for (double v : early) me += v;
    for (double v : late) ml += v;
    m.late_over_early =
        std::exp(ml / static_cast<double>(late.size()) - me / static_cast<double>(early.size()));
    m.trend_t = welch_t(early, late);
  }
  return m;
}

std::string describe(const Misfit& m) {
  std::string out = fmt::format(
      "The misfit lives mostly in {} (held-out NRMSE {:.4f} against a noise floor of {:.4f})",
      m.channel,
      m.channel == "x" ? m.channel_nrmse[0]
                       : (m.channel == "p1" ? m.channel_nrmse[1] : m.channel_nrmse[2]),
      m.channel == "x" ? m.channel_floor[0]
                       : (m.channel == "p1" ? m.channel_floor[1] : m.channel_floor[2]));
  if (!m.regressors.empty()) {
    out += fmt::format("; its rate follows {} best (correlation {:+.2f}", m.regressors[0].regressor,
                       m.regressors[0].correlation);
    if (m.regressors.size() > 1) {
      out +=
          fmt::format(", then {} {:+.2f}", m.regressors[1].regressor, m.regressors[1].correlation);
    }
    out += ")";
  }
  out += fmt::format("; {:.0f} % of its power above the white noise lies in {:g}-{:g} Hz",
                     100.0 * m.band_share, m.band_low_hz, m.band_high_hz);
  out += fmt::format("; the last third's error is {:.2f} times the first third's (t {:+.1f})",
                     m.late_over_early, m.trend_t);
  out += m.drifts ? ": it drifts over the capture (a changing operating condition such as the "
                    "oil warming up, not a constant fault)."
                  : ": no drift over the capture.";
  return out;
}

}  // namespace leakmon::model
