#include "model/spectral_line.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>
#include <vector>

namespace leakmon::model {
namespace {

// Hann-windowed, mean-free copy of a channel (gaps replaced by the previous sample).
std::vector<double> windowed(const std::vector<double>& v) {
  const std::size_t n = v.size();
  double mean = 0.0;
  std::size_t count = 0;
  for (double x : v) {
    if (std::isfinite(x)) {
      mean += x;
      ++count;
    }
  }
  mean /= static_cast<double>(std::max<std::size_t>(count, 1));
  std::vector<double> out(n);
  double last = mean;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isfinite(v[i])) last = v[i];
    const double w = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * static_cast<double>(i) /
                                          static_cast<double>(n - 1));
    out[i] = (last - mean) * w;
  }
  return out;
}

// Power of the windowed signals at an arbitrary frequency (a single DFT term).
double power_at(const std::vector<std::vector<double>>& signals, double f, double dt) {
  double total = 0.0;
  for (const auto& s : signals) {
    std::complex<double> acc = 0.0;
    const std::complex<double> step = std::polar(1.0, -2.0 * std::numbers::pi * f * dt);
    std::complex<double> rot = 1.0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      acc += s[i] * rot;
      rot *= step;
      if (i % 1024 == 0) rot /= std::abs(rot);  // keep the rotator on the unit circle
    }
    total += std::norm(acc);
  }
  return total;
}

}  // namespace

std::optional<SpectralLine> find_spectral_line(const MeasuredRecord& record,
                                               const LineSearch& search) {
  const std::vector<std::vector<double>> signals = {windowed(record.p1), windowed(record.p2)};
  std::size_t n = 1;
  while (n < record.size()) n *= 2;
  Eigen::FFT<double> fft;
  std::vector<double> power(n / 2 + 1, 0.0);
  for (const auto& s : signals) {
    std::vector<double> padded(s);
    padded.resize(n, 0.0);
    std::vector<std::complex<double>> spectrum;
    fft.fwd(spectrum, padded);
    for (std::size_t k = 0; k < power.size(); ++k) power[k] += std::norm(spectrum[k]);
  }
  const double df = 1.0 / (static_cast<double>(n) * record.dt);
  const auto bin = [&](double f) {
    return std::min(power.size() - 1, static_cast<std::size_t>(std::max(0.0, f / df)));
  };
  const std::size_t half = std::max<std::size_t>(8, bin(search.neighbourhood_hz));
  std::optional<SpectralLine> best;
  std::vector<double> around;
  for (std::size_t k = bin(search.low_hz); k <= bin(search.high_hz); ++k) {
    if (power[k] < power[k - 1] || power[k] < power[k + 1]) continue;  // local maxima only
    around.assign(power.begin() + static_cast<std::ptrdiff_t>(k - std::min(k, half)),
                  power.begin() + static_cast<std::ptrdiff_t>(std::min(power.size(), k + half)));
    std::nth_element(around.begin(),
                     around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2), around.end());
    const double median = std::max(around[around.size() / 2], 1e-300);
    const double prominence = power[k] / median;
    if (!best || prominence > best->prominence) {
      best = SpectralLine{static_cast<double>(k) * df, prominence};
    }
  }
  if (!best || best->prominence < search.min_prominence) return std::nullopt;
  // Refine within +-1 bin by golden-section search on the exact DFT power: the ripple's phase
  // must stay coherent over the whole record, so the frequency must be far finer than a bin.
  double lo = best->frequency_hz - df;
  double hi = best->frequency_hz + df;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = hi - g * (hi - lo);
  double b = lo + g * (hi - lo);
  double pa = power_at(signals, a, record.dt);
  double pb = power_at(signals, b, record.dt);
  for (int i = 0; i < 30; ++i) {
    if (pa > pb) {
      hi = b;
      b = a;
      pb = pa;
      a = hi - g * (hi - lo);
      pa = power_at(signals, a, record.dt);
    } else {
      lo = a;
      a = b;
      pa = pb;
      b = lo + g * (hi - lo);
      pb = power_at(signals, b, record.dt);
    }
  }
  best->frequency_hz = 0.5 * (lo + hi);
  return best;
}

}  // namespace leakmon::model
