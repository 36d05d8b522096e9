#include "model/segment_predictor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "model/piston_velocity.hpp"

namespace leakmon::model {
namespace {

constexpr double kBlowUp = 1e3;  // residual standing for a diverged simulation

double std_dev(const std::vector<double>& v, const std::vector<bool>& valid) {
  double sum = 0.0, sum2 = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!valid[i]) continue;
    sum += v[i];
    sum2 += v[i] * v[i];
    ++n;
  }
  if (n < 2) return 1.0;
  const double mean = sum / static_cast<double>(n);
  const double var = sum2 / static_cast<double>(n) - mean * mean;
  return var > 0.0 ? std::sqrt(var) : 1.0;
}

bool segment_valid(const MeasuredRecord& r, std::size_t begin, std::size_t length) {
  // The start's velocity reads kHalfWindow samples on either side; the noise floor's truth
  // starts kHalfWindow before the segment, from a velocity read as far before that.
  const std::size_t margin = PistonVelocity::kHalfWindow;
  if (begin < 2 * margin || begin + length + margin > r.size()) return false;
  for (std::size_t i = begin - 2 * margin; i < begin + length + margin; ++i) {
    if (!r.valid[i]) return false;
  }
  return true;
}

}  // namespace

SegmentPlan split_record(const MeasuredRecord& record, const SplitSettings& settings) {
  const auto block = static_cast<std::size_t>(std::lround(settings.block_s / record.dt));
  const auto length = static_cast<std::size_t>(std::lround(settings.segment_s / record.dt));
  SegmentPlan plan;
  for (std::size_t start = 0, index = 0; start + length <= record.size(); start += block, ++index) {
    auto& target = index % 2 == 0 ? plan.fitting : plan.held_out;
    for (std::size_t b = start; b + length <= std::min(start + block, record.size()); b += length) {
      if (segment_valid(record, b, length)) target.push_back({b, length});
    }
  }
  return plan;
}

std::vector<Segment> spread(std::span<const Segment> segments, std::size_t count) {
  if (segments.size() <= count) return {segments.begin(), segments.end()};
  std::vector<Segment> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) out.push_back(segments[i * segments.size() / count]);
  return out;
}

SegmentPredictor::SegmentPredictor(const MeasuredRecord& record, const sim::Parameters& rig)
    : record_(record), rig_(rig) {
  scales_ = {std_dev(record.x, record.valid), std_dev(record.p1, record.valid),
             std_dev(record.p2, record.valid)};
  const std::size_t n = record.size();
  velocity_.assign(n, 0.0);
  dp1_.assign(n, 0.0);
  dp2_.assign(n, 0.0);
  constexpr auto half = static_cast<std::size_t>(PistonVelocity::kHalfWindow);
  // A transducer lag's segment starts from p + tau dp/dt: a central difference put a noise of
  // 0.7 sigma / dt into it, which in slow phases cost more than the lag explained (818110); the
  // five-point least-squares slope has 0.32 sigma / dt.
  const auto slope = [&](const std::vector<double>& p, std::size_t k) {
    if (k >= 2 && k + 2 < n) {
      return (2.0 * (p[k + 2] - p[k - 2]) + p[k + 1] - p[k - 1]) / (10.0 * record.dt);
    }
    return (p[k + 1] - p[k - 1]) / (2.0 * record.dt);
  };
  for (std::size_t k = 1; k + 1 < n; ++k) {
    if (k >= half && k + half < n) velocity_[k] = PistonVelocity::at(record.x, k, record.dt);
    dp1_[k] = slope(record.p1, k);
    dp2_[k] = slope(record.p2, k);
  }
}

std::vector<double> SegmentPredictor::spool_positions(const ActuatorModel& model,
                                                      const ActuatorModel* before,
                                                      double onset_s) const {
  // Exact response of tau dxs/dt = sat((u + u0)/u_max) - xs to the held command; with an
  // onset, the spool of the model before it up to onset_s (a bias or a slower spool appears).
  const double decay = std::exp(-record_.dt / model.spool_tau());
  const double decay_before = before ? std::exp(-record_.dt / before->spool_tau()) : decay;
  std::vector<double> xs(record_.size());
  double state = 0.0;
  double u = 0.0;
  for (std::size_t k = 0; k < record_.size(); ++k) {
    xs[k] = state;
    if (std::isfinite(record_.u[k])) u = record_.u[k];
    if (before && record_.t[k] < onset_s) {
      state = decay_before * state + (1.0 - decay_before) * before->spool_input(u);
    } else {
      state = decay * state + (1.0 - decay) * model.spool_input(u);
    }
  }
  return xs;
}

SegmentPredictor::SpoolLaw SegmentPredictor::spool_law(const ActuatorModel& model,
                                                       const ActuatorModel* before,
                                                       double onset_s) {
  SpoolLaw law = {model.spool_tau(), model.coefficients().u_bias, model.coefficients().u_max};
  if (before) {
    // A spool whose tau is zero does not exist, so the zeros left without an onset cannot
    // stand for a model before one.
    law[3] = before->spool_tau();
    law[4] = before->coefficients().u_bias;
    law[5] = before->coefficients().u_max;
    law[6] = onset_s;
  }
  return law;
}

std::shared_ptr<const std::vector<double>> SegmentPredictor::shared_spool_positions(
    const ActuatorModel& model, const ActuatorModel* before, double onset_s) const {
  const SpoolLaw law = spool_law(model, before, onset_s);
  if (const auto* kept = spool_runs_.find(law)) return *kept;
  auto positions =
      std::make_shared<const std::vector<double>>(spool_positions(model, before, onset_s));
  spool_runs_.keep(law, positions);
  return positions;
}

template <typename Visit>
void SegmentPredictor::run(const ModelParameters& parameters, std::span<const Segment> segments,
                           Visit&& visit) const {
  const ActuatorModel after(parameters, rig_);
  // An effect starting inside the capture: the model without it up to onset_s.
  const bool switches = parameters.onset_s > 0.0;
  std::optional<ActuatorModel> before;
  if (switches) {
    ModelParameters early = parameters;
    early.effects = parameters.before;
    early.onset_s = 0.0;
    before.emplace(early, rig_);
  }
  const auto model_at = [&](double t) -> const ActuatorModel& {
    return switches && t < parameters.onset_s ? *before : after;
  };
  const auto spool =
      shared_spool_positions(after, switches ? &*before : nullptr, parameters.onset_s);
  const std::vector<double>& xs = *spool;
  // oil_temperature: the coefficients follow the measured oil temperature, sample by sample
  // (it changes over minutes; a missing reading holds the last one).
  const bool follows_temperature = parameters.effects.visc_slope > 0.0 && !record_.temp.empty();
  sim::ActuatorCoefficients at_temperature = after.coefficients();
  for (const auto& seg : segments) {
    const std::size_t k0 = seg.begin;
    const ActuatorModel* model = &model_at(record_.t[k0]);
    const auto& e = model->parameters().effects;
    ActuatorState s;
    s.xs = xs[k0];
    s.x = record_.x[k0];
    s.v = velocity_[k0];
    s.p1 = record_.p1[k0];
    s.p2 = record_.p2[k0];
    // Undo the transducer effects to start from the true pressures.
    if (e.offset != 0.0) (e.offset_channel == PressureChannel::p1 ? s.p1 : s.p2) -= e.offset;
    if (e.tau_s > 0.0) {
      const bool on_p1 = e.lag_channel == PressureChannel::p1;
      s.s = on_p1 ? s.p1 : s.p2;
      (on_p1 ? s.p1 : s.p2) += e.tau_s * (on_p1 ? dp1_[k0] : dp2_[k0]);
    }
    bool diverged = false;
    for (std::size_t j = 1; j < seg.length; ++j) {
      const std::size_t k = k0 + j;
      if (!diverged && follows_temperature) {
        const double T = record_.temp[k - 1];
        if (std::isfinite(T)) at_temperature = model->coefficients_at(T);
        model->advance(s, record_.u[k - 1], record_.t[k - 1], record_.dt, 0.0, at_temperature);
      } else if (!diverged) {
        model->advance(s, record_.u[k - 1], record_.t[k - 1], record_.dt);
        diverged = !(std::isfinite(s.x) && std::isfinite(s.p1) && std::isfinite(s.p2) &&
                     std::abs(s.x) < 10.0 * rig_.L && s.p1 < 1e9 && s.p2 < 1e9);
      }
      if (switches) {
        const ActuatorModel* now = &model_at(record_.t[k]);
        if (now != model) {
          // A transducer lag that starts now reads the pressure it starts from.
          const auto& started = now->parameters().effects;
          if (started.tau_s > 0.0 && model->parameters().effects.tau_s <= 0.0) {
            s.s = started.lag_channel == PressureChannel::p1 ? s.p1 : s.p2;
          }
          model = now;
        }
      }
      visit(k, model->read(s), diverged);
    }
  }
}

void SegmentPredictor::predict(const ModelParameters& parameters, std::span<const Segment> segments,
                               Prediction& out) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.x.assign(record_.size(), nan);
  out.p1.assign(record_.size(), nan);
  out.p2.assign(record_.size(), nan);
  run(parameters, segments, [&](std::size_t k, const Reading& r, bool diverged) {
    out.x[k] = diverged ? nan : r.x;
    out.p1[k] = diverged ? nan : r.p1;
    out.p2[k] = diverged ? nan : r.p2;
  });
}

std::size_t SegmentPredictor::residual_count(std::span<const Segment> segments) {
  std::size_t n = 0;
  for (const auto& s : segments) n += 3 * (s.length - 1);
  return n;
}

void SegmentPredictor::residuals(const ModelParameters& parameters,
                                 std::span<const Segment> segments, std::span<double> out) const {
  std::size_t i = 0;
  run(parameters, segments, [&](std::size_t k, const Reading& r, bool diverged) {
    if (diverged) {
      out[i++] = kBlowUp;
      out[i++] = kBlowUp;
      out[i++] = kBlowUp;
      return;
    }
    out[i++] = (r.x - record_.x[k]) / scales_.x;
    out[i++] = (r.p1 - record_.p1[k]) / scales_.p1;
    out[i++] = (r.p2 - record_.p2[k]) / scales_.p2;
  });
}

std::array<double, 3> SegmentPredictor::channel_nrmse(const Prediction& prediction,
                                                      std::span<const Segment> segments) const {
  const std::vector<double>* measured[3] = {&record_.x, &record_.p1, &record_.p2};
  const std::vector<double>* predicted[3] = {&prediction.x, &prediction.p1, &prediction.p2};
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c) {
    double err2 = 0.0, sum = 0.0, sum2 = 0.0;
    std::size_t n = 0;
    for (const auto& seg : segments) {
      for (std::size_t k = seg.begin + 1; k < seg.begin + seg.length; ++k) {
        const double m = (*measured[c])[k];
        double p = (*predicted[c])[k];
        if (!std::isfinite(p)) p = m + kBlowUp * scales_.p1;  // a diverged run counts as huge
        err2 += (p - m) * (p - m);
        sum += m;
        sum2 += m * m;
        ++n;
      }
    }
    if (n == 0) return {std::numeric_limits<double>::quiet_NaN()};
    const double mean = sum / static_cast<double>(n);
    const double var = std::max(sum2 / static_cast<double>(n) - mean * mean, 1e-30);
    out[static_cast<std::size_t>(c)] = std::sqrt(err2 / static_cast<double>(n) / var);
  }
  return out;
}

double SegmentPredictor::nrmse(const Prediction& prediction,
                               std::span<const Segment> segments) const {
  const auto c = channel_nrmse(prediction, segments);
  return (c[0] + c[1] + c[2]) / 3.0;
}

NoiseLevels SegmentPredictor::noise_levels() const {
  const auto sigma = [&](const std::vector<double>& y) {
    std::vector<double> d;
    d.reserve(y.size());
    for (std::size_t k = 1; k + 2 < y.size(); ++k) {
      if (!(record_.valid[k - 1] && record_.valid[k] && record_.valid[k + 1] &&
            record_.valid[k + 2]))
        continue;
      const double third = y[k + 2] - 3.0 * y[k + 1] + 3.0 * y[k] - y[k - 1];
      d.push_back(third * third);
    }
    if (d.empty()) return 0.0;
    // The mean square of the smallest 90 %: the largest tenth (fast transients) left out. A
    // median would be robust too but is coarse on readings quantised to one LSB (the third
    // differences take few distinct values); for Gaussian values the kept mean square is
    // 0.6231 times the full one (truncation at the 90 % quantile, |z| = 1.645).
    auto cut = d.begin() + static_cast<std::ptrdiff_t>(d.size() * 9 / 10);
    std::nth_element(d.begin(), cut, d.end());
    double sum = 0.0;
    for (auto it = d.begin(); it != cut; ++it) sum += *it;
    const double kept = static_cast<double>(cut - d.begin());
    return std::sqrt(sum / std::max(kept, 1.0) / (0.6231 * 20.0));
  };
  NoiseLevels n;
  n.x = sigma(record_.x);
  // The spool flow noise moves the two chamber pressures in opposite directions (a flow into
  // one chamber is a flow out of the other), so it shows in each pressure's third differences
  // but largely cancels in p1 + p2, where the two transducers' independent noises add: the
  // pressure transducers' noise is read there (both taken as equal).
  std::vector<double> sum(record_.size());
  for (std::size_t k = 0; k < sum.size(); ++k) sum[k] = record_.p1[k] + record_.p2[k];
  n.p1 = n.p2 = sigma(sum) / std::sqrt(2.0);
  n.spool_sigma = rig_.sigma_w;
  n.spool_tau = rig_.tau_w;
  return n;
}

std::array<double, 3> SegmentPredictor::noise_floor(const ModelParameters& parameters,
                                                    std::span<const Segment> segments,
                                                    const NoiseLevels& noise, std::uint64_t seed,
                                                    int repeats, int pieces,
                                                    FloorRinging* ringing) const {
  const ActuatorModel model(parameters, rig_);
  const std::vector<double> xs = spool_positions(model);
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  // The flow noise is an Ornstein-Uhlenbeck process; over a sample the plant integrates its
  // mean, whose variance and correlation with the next sample's mean follow from tau_w / dt.
  const double a = noise.spool_tau / record_.dt;
  const double e = std::exp(-1.0 / a);
  const double mean_var = noise.spool_sigma * noise.spool_sigma * 2.0 * a * (1.0 - a * (1.0 - e));
  const double next_cov = noise.spool_sigma * noise.spool_sigma * a * a * (1.0 - e) * (1.0 - e);
  const double rho = mean_var > 0.0 ? std::clamp(next_cov / mean_var, 0.0, 0.99) : 0.0;
  const double w_sigma = std::sqrt(std::max(mean_var, 0.0));
  const double w_innovation = w_sigma * std::sqrt(1.0 - rho * rho);
  const double sigmas[3] = {noise.x, noise.p1, noise.p2};
  const std::vector<double>* measured[3] = {&record_.x, &record_.p1, &record_.p2};
  double err2[3] = {0.0, 0.0, 0.0};
  std::size_t n = 0;
  double drawn_third2 = 0.0;
  std::size_t drawn_thirds = 0;
  // The truth runs from kLeadIn samples before the segment's start, so that the guess starts
  // from a state read off the drawn readings as the prediction's is off the capture: the
  // velocity from their cubic fit over +-kLeadIn samples. A start velocity drawn as the
  // estimate's noise alone missed its bias on a rig ringing near 100 Hz (5 samples a period,
  // far beyond what +-6 samples follow): the true model of a 211 kg rig hunting at its
  // hydraulic mode scored 0.23 in p without any noise, the floor 0.015.
  constexpr std::size_t kLeadIn = static_cast<std::size_t>(PistonVelocity::kHalfWindow);
  std::vector<double> read_x, read_p1, read_p2;
  for (int r = 0; r < repeats; ++r) {
    for (const auto& seg : segments) {
      const std::size_t k0 = seg.begin;
      const std::size_t first = k0 - kLeadIn;  // segments keep 2 kLeadIn valid samples before
      const std::size_t samples = seg.length + kLeadIn;
      read_x.assign(samples, 0.0);
      read_p1.assign(samples, 0.0);
      read_p2.assign(samples, 0.0);
      ActuatorState truth;
      truth.xs = xs[first];
      truth.x = record_.x[first];
      truth.v = velocity_[first];
      truth.p1 = record_.p1[first];
      truth.p2 = record_.p2[first];
      truth.s = truth.p1;
      const auto read_truth = [&](std::size_t i) {
        const Reading t = model.read(truth);
        read_x[i] = t.x + sigmas[0] * normal(random);
        read_p1[i] = t.p1 + sigmas[1] * normal(random);
        read_p2[i] = t.p2 + sigmas[2] * normal(random);
      };
      read_truth(0);
      double w = w_sigma * normal(random);
      // Finer: the process itself at the pieces' spacing, each piece holding the mean of its
      // two ends (the simulator interpolates its noise grid linearly).
      const double piece = record_.dt / pieces;
      const double piece_rho = std::exp(-piece / std::max(noise.spool_tau, 1e-9));
      const double piece_innovation =
          noise.spool_sigma * std::sqrt(std::max(1.0 - piece_rho * piece_rho, 0.0));
      double w_end = noise.spool_sigma * normal(random);
      for (std::size_t i = 1; i < samples; ++i) {
        const std::size_t k = first + i;
        if (pieces <= 1) {
          model.advance(truth, record_.u[k - 1], record_.t[k - 1], record_.dt, w);
        } else {
          for (int p = 0; p < pieces; ++p) {
            const double w_start = w_end;
            w_end = piece_rho * w_end + piece_innovation * normal(random);
            model.advance(truth, record_.u[k - 1], record_.t[k - 1] + p * piece, piece,
                          0.5 * (w_start + w_end));
          }
        }
        w = rho * w + w_innovation * normal(random);
        read_truth(i);
      }
      // The guess: the model's own spool, the readings at the start, the velocity fitted to them.
      ActuatorState guess;
      guess.xs = xs[k0];
      guess.x = read_x[kLeadIn];
      guess.v = kLeadIn + kLeadIn < samples ? PistonVelocity::at(read_x, kLeadIn, record_.dt) : 0.0;
      guess.p1 = read_p1[kLeadIn];
      guess.p2 = read_p2[kLeadIn];
      guess.s = guess.p1;
      double recent[4] = {0.0, 0.0, 0.0, 0.0};  // the drawn readings' p1 - p2, newest last
      for (std::size_t j = 1; j < seg.length; ++j) {
        const std::size_t k = k0 + j;
        model.advance(guess, record_.u[k - 1], record_.t[k - 1], record_.dt);
        const Reading g = model.read(guess);
        const double read[3] = {read_x[kLeadIn + j], read_p1[kLeadIn + j], read_p2[kLeadIn + j]};
        const double guess_read[3] = {g.x, g.p1, g.p2};
        for (int c = 0; c < 3; ++c) {
          const double d = guess_read[c] - read[c];
          if (std::isfinite(d)) err2[c] += d * d;
        }
        recent[0] = recent[1];
        recent[1] = recent[2];
        recent[2] = recent[3];
        recent[3] = read[1] - read[2];
        if (j >= 4) {
          const double third = recent[3] - 3.0 * recent[2] + 3.0 * recent[1] - recent[0];
          if (std::isfinite(third)) {
            drawn_third2 += third * third;
            ++drawn_thirds;
          }
        }
        ++n;
      }
    }
  }
  std::array<double, 3> out{};
  if (n == 0) return out;
  if (ringing) {
    double measured_third2 = 0.0;
    std::size_t measured_thirds = 0;
    for (const auto& seg : segments) {
      for (std::size_t k = seg.begin + 4; k < seg.begin + seg.length; ++k) {
        if (!(record_.valid[k - 3] && record_.valid[k - 2] && record_.valid[k - 1] &&
              record_.valid[k]))
          continue;
        const auto difference = [&](std::size_t i) { return record_.p1[i] - record_.p2[i]; };
        const double third =
            difference(k) - 3.0 * difference(k - 1) + 3.0 * difference(k - 2) - difference(k - 3);
        measured_third2 += third * third;
        ++measured_thirds;
      }
    }
    ringing->measured =
        measured_thirds ? measured_third2 / static_cast<double>(measured_thirds) : 0.0;
    ringing->drawn = drawn_thirds ? drawn_third2 / static_cast<double>(drawn_thirds) : 0.0;
  }
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0, sum2 = 0.0;
    std::size_t m = 0;
    for (const auto& seg : segments) {
      for (std::size_t k = seg.begin + 1; k < seg.begin + seg.length; ++k) {
        const double y = (*measured[c])[k];
        sum += y;
        sum2 += y * y;
        ++m;
      }
    }
    const double mean = sum / static_cast<double>(m);
    const double var = std::max(sum2 / static_cast<double>(m) - mean * mean, 1e-30);
    out[static_cast<std::size_t>(c)] = std::sqrt(err2[c] / static_cast<double>(n) / var);
  }
  return out;
}

double SegmentPredictor::nrmse(const ModelParameters& parameters,
                               std::span<const Segment> segments) const {
  Prediction p;
  predict(parameters, segments, p);
  return nrmse(p, segments);
}

std::vector<double> segment_errors(const SegmentPredictor& predictor,
                                   const ModelParameters& parameters,
                                   std::span<const Segment> segments) {
  std::vector<double> r(SegmentPredictor::residual_count(segments));
  predictor.residuals(parameters, segments, r);
  std::vector<double> out;
  std::size_t i = 0;
  for (const auto& seg : segments) {
    const std::size_t n = 3 * (seg.length - 1);
    double sum = 0.0;
    for (std::size_t j = 0; j < n; ++j, ++i) sum += r[i] * r[i];
    out.push_back(sum / static_cast<double>(n));
  }
  return out;
}

std::vector<double> summed_errors_at_onsets(const SegmentPredictor& predictor,
                                            const ModelParameters& parameters,
                                            std::span<const Segment> segments,
                                            std::span<const double> onsets, double settle_s) {
  const MeasuredRecord& record = predictor.record();
  ModelParameters throughout_before = parameters;
  throughout_before.onset_s = record.t.back() + 1.0;
  ModelParameters throughout_after = parameters;
  throughout_after.onset_s = 0.0;
  const auto errors_before = segment_errors(predictor, throughout_before, segments);
  const auto errors_after = segment_errors(predictor, throughout_after, segments);
  ModelParameters trial = parameters;
  std::vector<double> sums;
  std::vector<Segment> around;
  for (const double onset : onsets) {
    trial.onset_s = onset;
    double sum = 0.0;
    around.clear();
    for (std::size_t k = 0; k < segments.size(); ++k) {
      if (!predictor.reaches(segments[k], onset)) {
        sum += errors_before[k];
      } else if (record.t[segments[k].begin] >= onset + settle_s) {
        sum += errors_after[k];
      } else {
        around.push_back(segments[k]);
      }
    }
    for (double e : segment_errors(predictor, trial, around)) sum += e;
    sums.push_back(sum);
  }
  return sums;
}

}  // namespace leakmon::model
