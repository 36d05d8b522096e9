#include "model/segment_predictor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace leakmon::model {
namespace {

constexpr int kVelocityHalfWindow = 3;  // +-3 samples: 0.6 mm/s noise from 6 um position noise
constexpr double kBlowUp = 1e3;         // residual standing for a diverged simulation

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
  const std::size_t margin = kVelocityHalfWindow;
  if (begin < margin || begin + length + margin > r.size()) return false;
  for (std::size_t i = begin - margin; i < begin + length + margin; ++i) {
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
  double weight = 0.0;
  for (int i = 1; i <= kVelocityHalfWindow; ++i) weight += 2.0 * i * i;
  for (std::size_t k = kVelocityHalfWindow; k + kVelocityHalfWindow < n; ++k) {
    double slope = 0.0;
    for (int i = -kVelocityHalfWindow; i <= kVelocityHalfWindow; ++i) {
      slope += i * record.x[static_cast<std::size_t>(static_cast<long>(k) + i)];
    }
    velocity_[k] = slope / (weight * record.dt);
    dp1_[k] = (record.p1[k + 1] - record.p1[k - 1]) / (2.0 * record.dt);
    dp2_[k] = (record.p2[k + 1] - record.p2[k - 1]) / (2.0 * record.dt);
  }
}

std::vector<double> SegmentPredictor::spool_positions(const ActuatorModel& model) const {
  // Exact response of tau dxs/dt = sat((u + u0)/u_max) - xs to the held command.
  const double decay = std::exp(-record_.dt / model.spool_tau());
  std::vector<double> xs(record_.size());
  double state = 0.0;
  double u = 0.0;
  for (std::size_t k = 0; k < record_.size(); ++k) {
    xs[k] = state;
    if (std::isfinite(record_.u[k])) u = record_.u[k];
    state = decay * state + (1.0 - decay) * model.spool_input(u);
  }
  return xs;
}

template <typename Visit>
void SegmentPredictor::run(const ModelParameters& parameters, std::span<const Segment> segments,
                           Visit&& visit) const {
  const ActuatorModel model(parameters, rig_);
  const std::vector<double> xs = spool_positions(model);
  const auto& e = parameters.effects;
  for (const auto& seg : segments) {
    const std::size_t k0 = seg.begin;
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
      if (!diverged) {
        model.advance(s, record_.u[k - 1], record_.t[k - 1], record_.dt);
        diverged = !(std::isfinite(s.x) && std::isfinite(s.p1) && std::isfinite(s.p2) &&
                     std::abs(s.x) < 10.0 * rig_.L && s.p1 < 1e9 && s.p2 < 1e9);
      }
      visit(k, model.read(s), diverged);
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

double SegmentPredictor::nrmse(const Prediction& prediction,
                               std::span<const Segment> segments) const {
  const std::vector<double>* measured[3] = {&record_.x, &record_.p1, &record_.p2};
  const std::vector<double>* predicted[3] = {&prediction.x, &prediction.p1, &prediction.p2};
  double total = 0.0;
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
    if (n == 0) return std::numeric_limits<double>::quiet_NaN();
    const double mean = sum / static_cast<double>(n);
    const double var = std::max(sum2 / static_cast<double>(n) - mean * mean, 1e-30);
    total += std::sqrt(err2 / static_cast<double>(n) / var);
  }
  return total / 3.0;
}

double SegmentPredictor::nrmse(const ModelParameters& parameters,
                               std::span<const Segment> segments) const {
  Prediction p;
  predict(parameters, segments, p);
  return nrmse(p, segments);
}

}  // namespace leakmon::model
