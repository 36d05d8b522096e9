#include "detect/sensor_plausibility.hpp"

#include <algorithm>
#include <cmath>

namespace leakmon::detect {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Expected false "frozen" reports per channel and hour that the run length is chosen for.
constexpr double kFalseFrozenPerHour = 1e-6;
// The run length from white noise is doubled: real transducers low-pass their noise (successive
// readings are correlated over a sample or two) and a configured sigma may be optimistic.
constexpr double kFrozenSafety = 2.0;
// Saturation and dropout must last this long: long against one hop (40 ms), short against the
// 5 s in which a fault must be named.
constexpr double kSaturatedSeconds = 0.25;
constexpr double kDropoutSeconds = 0.25;
// A rejected spike is a fault at once: a sample off its neighbours by more than the noise floor
// plus twice their range and back within one sample is no pressure or position the rig can
// make (see the Hampel test in push()). The fault holds until the channel has been quiet this
// long: interference comes a few times a minute, so a shorter hold would chatter between spikes.
constexpr double kSpikeQuietSeconds = 60.0;
// A fault's condition must stay away this long before the channel is ok again (the status is
// maintenance_required meanwhile), so a flickering fault does not chatter.
constexpr double kRecoverySeconds = 2.0;
// Hampel threshold in noise sigmas (of reading noise including quantisation). The centre minus
// the median of four neighbours has a sigma of at most 1.3 sigma_eff; 8 sigma_eff is more than
// 6 of those: about 1e-9 per sample, and a rejected healthy sample costs nothing but a tiny
// smoothing.
constexpr double kSpikeSigmas = 8.0;
// The threshold also follows what the channel itself does between samples: at least this many
// times its mean deviation from the neighbours' median over the last kDeviationSeconds, each
// sample's deviation clipped at kDeviationClip times the mean so that a transient lifts it
// slowly. On the paper's rig that mean is the noise's (5 kPa) and the floor above rules. Rigs
// whose hydraulic mode sits near a third of the sample rate (MODEL.md "Other rigs": small
// masses behind large valves) swing 40-100 kPa from sample to sample all the time, every
// healthy sample a hair off the fixed threshold: 12 of 50 such rigs reported "spikes". A spike
// of MPa still stands far above either.
constexpr double kDeviationSigmas = 6.0;
constexpr double kDeviationClip = 3.0;
constexpr double kDeviationSeconds = 0.5;
// An out-of-band sample takes this many in-band samples back from the saturation count: a
// reading pinned at a range end with noise still leaves the band now and then.
constexpr std::uint32_t kBandLeak = 4;

std::uint32_t samples(double seconds, double rate) {
  return static_cast<std::uint32_t>(std::max(1.0, std::ceil(seconds * rate)));
}

}  // namespace

std::string_view to_string(SensorFault fault) {
  switch (fault) {
    case SensorFault::none:
      return "none";
    case SensorFault::frozen:
      return "frozen";
    case SensorFault::saturated:
      return "saturated";
    case SensorFault::spikes:
      return "spikes";
    case SensorFault::dropout:
      return "dropout";
  }
  return "unknown";
}

io::DeviceStatus device_status(SensorFault fault) {
  switch (fault) {
    case SensorFault::none:
      return io::DeviceStatus::ok;
    case SensorFault::frozen:
    case SensorFault::dropout:
      return io::DeviceStatus::failure;
    case SensorFault::saturated:
    case SensorFault::spikes:
      return io::DeviceStatus::out_of_specification;
  }
  return io::DeviceStatus::failure;
}

PlausibilityLimits plausibility_limits(const TransducerSpec& spec, double sample_rate_hz) {
  PlausibilityLimits limits;
  const double q = std::max(0.0, spec.resolution);
  const double sigma = std::max(0.0, spec.noise_sigma);
  // Frozen. A quantised reading of a constant true value repeats when its noise keeps it in one
  // code; worst case the value sits at a code's centre: p = P(|n| < q/2) = erf(q / (2 sqrt2
  // sigma)). A run of L equal readings starting at a given sample has probability p^(L-1); over
  // an hour's N = 3600 fs samples the expected number of false runs is N p^(L-1). Asking for
  // kFalseFrozenPerHour gives L - 1 = ln(kFalseFrozenPerHour / N) / ln p, doubled (kFrozenSafety).
  // MODEL.md's pressure transducer (q 5.05 kPa, sigma 5 kPa): p = 0.386, L = 62 (124 ms at
  // 500 Hz); its position transducer (q 10 um, sigma 5 um): p = 0.683, L = 150 (300 ms).
  // Without noise a constant reading is normal: no frozen check.
  if (sigma > 0.0) {
    const double p = q > 0.0 ? std::erf(q / (2.0 * std::sqrt(2.0) * sigma)) : 0.0;
    const double per_hour = 3600.0 * sample_rate_hz;
    double run = 3.0;  // unquantised noisy readings never repeat: three equal ones are a fault
    if (p > 0.0 && p < 1.0) {
      run = 1.0 + std::ceil(std::log(kFalseFrozenPerHour / per_hour) / std::log(p));
    }
    limits.frozen_run = static_cast<std::uint32_t>(std::ceil(kFrozenSafety * run));
    // A quarter of it: p^(L/4) still makes such runs rare (pressure: 15 repeats, p^14 = 2e-6
    // per sample, a few a day at rest), and a frozen stream is distrusted after 30 ms.
    limits.suspect_run = std::max<std::uint32_t>(3, limits.frozen_run / 4);
  }
  limits.saturated_run = samples(kSaturatedSeconds, sample_rate_hz);
  limits.dropout_run = samples(kDropoutSeconds, sample_rate_hz);
  limits.spike_quiet = samples(kSpikeQuietSeconds, sample_rate_hz);
  limits.recovery = samples(kRecoverySeconds, sample_rate_hz);
  const double sigma_eff = std::sqrt(sigma * sigma + q * q / 12.0);
  limits.spike_sigma = std::max(kSpikeSigmas * sigma_eff, 2.0 * q);
  // |n - median of four|, n and the four Gaussian: sigma_eff sqrt(1 + 0.35) sqrt(2 / pi).
  limits.deviation_noise = 0.93 * sigma_eff;
  limits.deviation_memory = 1.0 / (kDeviationSeconds * sample_rate_hz);
  limits.deviation_warmup = samples(2.0 * kDeviationSeconds, sample_rate_hz);
  // A transducer whose range starts at or above 0 (pressure) reads exactly 0 only when it is
  // dead or pinned below its range: the physics cannot give a noise-free zero.
  limits.zero_is_dropout = std::isfinite(spec.min) && spec.min >= 0.0;
  return limits;
}

SensorPlausibility::SensorPlausibility(const TransducerSpec& spec, double sample_rate_hz)
    : spec_(spec),
      limits_(plausibility_limits(spec, sample_rate_hz)),
      deviation_scale_(limits_.deviation_noise) {
  history_.fill(kNaN);
}

void SensorPlausibility::reconfigure(const TransducerSpec& spec, double sample_rate_hz) {
  spec_ = spec;
  limits_ = plausibility_limits(spec, sample_rate_hz);
}

io::DeviceStatus SensorPlausibility::status() const {
  if (reported_ == SensorFault::none) return io::DeviceStatus::ok;
  if (recovering()) return io::DeviceStatus::maintenance_required;
  return device_status(reported_);
}

bool SensorPlausibility::suspect() const {
  if (!spec_.enabled) return false;
  // Spikes alone leave the stream usable: each rejected sample has been replaced by its
  // neighbours' median, so the leak decision goes on while the fault is reported.
  if ((reported_ != SensorFault::none && reported_ != SensorFault::spikes) || band_run_ > 0) {
    return true;
  }
  if (limits_.zero_is_dropout && zero_run_ > 0) return true;
  return limits_.suspect_run > 0 && repeat_run_ >= limits_.suspect_run;
}

SensorFault SensorPlausibility::condition() const {
  if (nan_run_ >= limits_.dropout_run) return SensorFault::dropout;
  if (limits_.zero_is_dropout && zero_run_ >= limits_.dropout_run) return SensorFault::dropout;
  if (band_run_ >= limits_.saturated_run) return SensorFault::saturated;
  // Exact repeats at a range end are saturation (above), not a stalled converter.
  if (limits_.frozen_run > 0 && repeat_run_ >= limits_.frozen_run && band_run_ == 0) {
    // Where no range end is configured (a position transducer), a constant reached by a leap
    // no position can make is the converter pinned at a limit, or with exactly 0 a lost
    // signal; a stalled converter holds the value the signal had.
    const bool range_known = std::isfinite(spec_.min) && std::isfinite(spec_.max);
    if (range_known || !run_began_with_jump_) return SensorFault::frozen;
    return last_value_ == 0.0 ? SensorFault::dropout : SensorFault::saturated;
  }
  if (last_spike_ != 0 && samples_ - last_spike_ <= limits_.spike_quiet) {
    return SensorFault::spikes;
  }
  return SensorFault::none;
}

double SensorPlausibility::push(double value) noexcept {
  constexpr std::size_t n = 2 * kDelay + 1;
  history_[next_] = value;
  next_ = (next_ + 1) % n;
  ++samples_;
  if (!spec_.enabled) {
    return samples_ > kDelay ? history_[(next_ + kDelay) % n] : kNaN;
  }

  // Runs on the raw newest value.
  if (std::isnan(value)) {
    ++nan_run_;
    repeat_run_ = 0;
    band_run_ = 0;
    zero_run_ = 0;
  } else {
    nan_run_ = 0;
    if (value != last_value_) {
      // The same test as for a spike (below), on the newest value against the four before it.
      double low = last_value_, high = last_value_;
      for (std::size_t k = 2; k <= 2 * kDelay + 1; ++k) {
        const double before = history_[(next_ + n - k) % n];
        low = std::min(low, before);
        high = std::max(high, before);
      }
      run_began_with_jump_ =
          std::isfinite(low) && std::isfinite(high) &&
          std::abs(value - last_value_) > limits_.spike_sigma + 2.0 * (high - low);
    }
    repeat_run_ = value == last_value_ ? repeat_run_ + 1 : 1;
    const bool in_band =
        value <= spec_.min + 1.5 * spec_.resolution || value >= spec_.max - 1.5 * spec_.resolution;
    // A dropout to zeros that has just ended leaves no saturation behind (its zeros sat in the
    // bottom band too): the reading is back, not pinned at the range end.
    if (value != 0.0 && limits_.zero_is_dropout && zero_run_ >= limits_.dropout_run) band_run_ = 0;
    // Counted up to twice the saturation run only: enough margin for a noisy reading at the range
    // end, and a channel that comes back after a long saturation is trusted again within
    // 2 saturated_run / kBandLeak samples instead of a quarter of the fault's length.
    band_run_ = in_band ? std::min(band_run_ + 1, 2 * limits_.saturated_run)
                        : (band_run_ > kBandLeak ? band_run_ - kBandLeak : 0);
    zero_run_ = value == 0.0 ? zero_run_ + 1 : 0;
  }
  last_value_ = value;

  // Hampel test of the centre against the median of its four neighbours. The threshold adds
  // twice the neighbours' range: the rig's pressures ring near 60 Hz (8 samples a period) with
  // hundreds of kPa, so a healthy centre can sit well off the median; on 20 min of simulated
  // data of both controllers it never sat more than 0.9 ranges (beyond the noise floor) off.
  // A spike of MPa is still caught whenever its neighbours span less than about half of it,
  // i.e. everywhere but in the steepest transients.
  double out = kNaN;
  if (samples_ > kDelay) {
    const std::size_t centre = (next_ + kDelay) % n;
    out = history_[centre];
    if (samples_ >= n && !std::isnan(out)) {
      std::array<double, 4> neighbours{history_[next_ % n], history_[(next_ + 1) % n],
                                       history_[(next_ + 3) % n], history_[(next_ + 4) % n]};
      if (std::none_of(neighbours.begin(), neighbours.end(),
                       [](double v) { return std::isnan(v); })) {
        std::sort(neighbours.begin(), neighbours.end());
        const double median = 0.5 * (neighbours[1] + neighbours[2]);
        const double range = neighbours[3] - neighbours[0];
        const double deviation = std::abs(out - median);
        const double floor = std::max(limits_.spike_sigma, kDeviationSigmas * deviation_scale_);
        if (deviation <= floor + 2.0 * range) {
          deviation_scale_ +=
              limits_.deviation_memory *
              (std::min(deviation,
                        kDeviationClip * std::max(deviation_scale_, limits_.deviation_noise)) -
               deviation_scale_);
        } else {
          out = median;
          history_[centre] = median;  // later tests see the cleaned value as a neighbour
          ++spikes_rejected_;
          // Replaced from the first sample, named once the scale has seen the channel move.
          if (samples_ > limits_.deviation_warmup) last_spike_ = samples_ - kDelay;
        }
      }
    }
  }

  const SensorFault now = condition();
  if (now != SensorFault::none) {
    active_ = now;
    reported_ = now;
    clean_run_ = 0;
  } else {
    active_ = SensorFault::none;
    if (reported_ != SensorFault::none && ++clean_run_ >= limits_.recovery) {
      reported_ = SensorFault::none;
    }
  }
  return out;
}

}  // namespace leakmon::detect
