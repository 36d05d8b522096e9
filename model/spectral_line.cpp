#include "model/spectral_line.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>
#include <vector>

namespace leakmon::model {
namespace {

// The signal a ripple moves most and the hydraulic noise least: the measured supply pressure
// when there is one, else p1 + p2. First differences whiten it: the steps put most of the
// power below a few hertz, and differencing keeps that out of the line's neighbourhood.
std::vector<double> ripple_signal(const MeasuredRecord& record, bool& from_supply) {
  const std::size_t n = record.size();
  std::size_t finite_ps = 0;
  for (double v : record.ps) finite_ps += std::isfinite(v) ? 1 : 0;
  from_supply = !record.ps.empty() && finite_ps >= n / 2;
  std::vector<double> level(n);
  for (std::size_t k = 0; k < n; ++k) {
    level[k] = from_supply ? record.ps[k] : record.p1[k] + record.p2[k];
  }
  std::vector<double> out(n, std::nan(""));
  for (std::size_t k = 1; k < n; ++k) out[k] = level[k] - level[k - 1];
  return out;
}

// The signal on [begin, end) only, mean-free and Hann-windowed; zero elsewhere and at gaps.
std::vector<double> tapered(const std::vector<double>& signal, std::size_t begin, std::size_t end) {
  std::vector<double> out(signal.size(), 0.0);
  double mean = 0.0;
  std::size_t count = 0;
  for (std::size_t k = begin; k < end; ++k) {
    if (!std::isfinite(signal[k])) continue;
    mean += signal[k];
    ++count;
  }
  mean /= static_cast<double>(std::max<std::size_t>(count, 1));
  const auto length = static_cast<double>(end - begin);
  for (std::size_t k = begin; k < end; ++k) {
    if (!std::isfinite(signal[k])) continue;
    const double position = (static_cast<double>(k - begin) + 0.5) / length;
    out[k] = (signal[k] - mean) * (0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * position));
  }
  return out;
}

// One DFT term at an arbitrary frequency, phase referred to t = 0 (sample 0).
std::complex<double> amplitude_at(const std::vector<double>& s, double f, double dt) {
  std::complex<double> acc = 0.0;
  const std::complex<double> step = std::polar(1.0, -2.0 * std::numbers::pi * f * dt);
  std::complex<double> rot = 1.0;
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (s[k] != 0.0) acc += s[k] * rot;
    rot *= step;
    if (k % 1024 == 0) rot /= std::abs(rot);  // keep the rotator on the unit circle
  }
  return acc;
}

// Golden-section search for the largest DFT power within +-half_width of f: the phase must
// stay coherent over the whole signal, so the frequency must be far finer than an FFT bin.
double strongest_near(const std::vector<double>& s, double dt, double f, double half_width) {
  double lo = f - half_width;
  double hi = f + half_width;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = hi - g * (hi - lo);
  double b = lo + g * (hi - lo);
  double pa = std::norm(amplitude_at(s, a, dt));
  double pb = std::norm(amplitude_at(s, b, dt));
  for (int i = 0; i < 30; ++i) {
    if (pa > pb) {
      hi = b;
      b = a;
      pb = pa;
      a = hi - g * (hi - lo);
      pa = std::norm(amplitude_at(s, a, dt));
    } else {
      lo = a;
      a = b;
      pa = pb;
      b = lo + g * (hi - lo);
      pb = std::norm(amplitude_at(s, b, dt));
    }
  }
  return 0.5 * (lo + hi);
}

struct Peak {
  double frequency_hz = 0.0;
  double prominence = 0.0;
};

// The `count` most prominent local maxima of the power spectrum in the search band, most
// prominent first, each refined to a fraction of a bin.
std::vector<Peak> most_prominent_peaks(const std::vector<double>& s, double dt,
                                       const LineSearch& search, std::size_t count) {
  std::size_t n = 1;
  while (n < s.size()) n *= 2;
  std::vector<double> padded(s);
  padded.resize(n, 0.0);
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> spectrum;
  fft.fwd(spectrum, padded);
  std::vector<double> power(n / 2 + 1);
  for (std::size_t k = 0; k < power.size(); ++k) power[k] = std::norm(spectrum[k]);
  const double df = 1.0 / (static_cast<double>(n) * dt);
  const auto bin = [&](double f) {
    return std::clamp<std::size_t>(static_cast<std::size_t>(std::max(0.0, f / df)), 1,
                                   power.size() - 2);
  };
  const std::size_t half = std::max<std::size_t>(8, bin(search.neighbourhood_hz));
  std::vector<Peak> peaks;
  std::vector<double> around;
  for (std::size_t k = bin(search.low_hz); k <= bin(search.high_hz); ++k) {
    if (power[k] < power[k - 1] || power[k] < power[k + 1]) continue;
    around.assign(power.begin() + static_cast<std::ptrdiff_t>(k - std::min(k, half)),
                  power.begin() + static_cast<std::ptrdiff_t>(std::min(power.size(), k + half)));
    std::nth_element(around.begin(),
                     around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2), around.end());
    peaks.push_back(
        {static_cast<double>(k) * df, power[k] / std::max(around[around.size() / 2], 1e-300)});
  }
  const auto more_prominent = [](const Peak& a, const Peak& b) {
    return a.prominence > b.prominence;
  };
  if (peaks.size() > count) {
    std::partial_sort(peaks.begin(), peaks.begin() + static_cast<std::ptrdiff_t>(count),
                      peaks.end(), more_prominent);
    peaks.resize(count);
  } else {
    std::sort(peaks.begin(), peaks.end(), more_prominent);
  }
  for (Peak& peak : peaks) peak.frequency_hz = strongest_near(s, dt, peak.frequency_hz, df);
  return peaks;
}

// The second half's coherent statistic at f, on the first half's phase there (see the header).
double held_out_z(const std::vector<double>& first, const std::vector<double>& second, double f,
                  double dt, const LineSearch& search) {
  const std::complex<double> phase = amplitude_at(first, f, dt);
  const std::complex<double> tested = amplitude_at(second, f, dt);
  // Noise level from neighbouring frequencies, median / ln 2: the mean of an exponentially
  // distributed power, robust to another line nearby.
  std::vector<double> noise;
  for (double offset = search.noise_offset_low_hz; offset <= search.noise_offset_high_hz + 1e-9;
       offset += search.noise_step_hz) {
    for (double sign : {-1.0, 1.0}) {
      noise.push_back(std::norm(amplitude_at(second, f + sign * offset, dt)));
    }
  }
  std::nth_element(noise.begin(), noise.begin() + static_cast<std::ptrdiff_t>(noise.size() / 2),
                   noise.end());
  const double noise_power = std::max(noise[noise.size() / 2] / std::numbers::ln2, 1e-300);
  const double projection = (tested * std::conj(phase)).real() / std::max(std::abs(phase), 1e-300);
  return projection / std::sqrt(noise_power / 2.0);
}

}  // namespace

std::optional<SpectralLine> find_spectral_line(const MeasuredRecord& record,
                                               const LineSearch& search) {
  const std::size_t n = record.size();
  if (n < 4) return std::nullopt;
  SpectralLine line;
  const std::vector<double> signal = ripple_signal(record, line.from_supply_column);
  // Contiguous halves: alternating blocks (as the model fit uses) would put comb teeth
  // 1 / (block period) around the line, nearly as tall as the line itself.
  const std::vector<double> first = tapered(signal, 1, n / 2);
  const std::vector<double> second = tapered(signal, n / 2, n);
  const std::vector<Peak> peaks = most_prominent_peaks(first, record.dt, search, search.candidates);
  if (peaks.empty()) return std::nullopt;
  double f = 0.0;
  for (std::size_t i = 0; i < peaks.size(); ++i) {
    const double z = held_out_z(first, second, peaks[i].frequency_hz, record.dt, search);
    if (i == 0 || z > line.held_out_z) {
      line.held_out_z = z;
      line.prominence = peaks[i].prominence;
      f = peaks[i].frequency_hz;
    }
  }

  // The frequency the ripple fit starts from: refined on the whole record (fitting, not
  // testing), where the line is narrowest.
  const std::vector<double> whole = tapered(signal, 1, n);
  line.frequency_hz =
      strongest_near(whole, record.dt, f, 2.0 / (static_cast<double>(n) * record.dt));
  return line;
}

}  // namespace leakmon::model
