#include "daemon/actuator_monitor.hpp"

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <limits>

#include "detect/factory.hpp"

namespace leakmon::daemon {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// 1 l/min = 1/60000 m^3/s; 1 MPa = 1e6 Pa.
constexpr double kLpmPerM3s = 60000.0;

double value_at(const Sample& sample, int index) {
  return index < 0 ? kNaN : sample.values[static_cast<std::size_t>(index)];
}

std::unique_ptr<detect::Detector> build_detector(const ActuatorConfig& config,
                                                 const ChannelLayout& layout,
                                                 std::int64_t period_ns) {
  detect::AvailableSignals signals;
  signals.p1 = layout.p1 >= 0;
  signals.p2 = layout.p2 >= 0;
  signals.u = layout.u >= 0;
  signals.x = layout.x >= 0;
  const double hop_seconds =
      static_cast<double>(config.features.step) * static_cast<double>(period_ns) / 1e9;
  const config::ConfigNode* options = config.detector_options ? &*config.detector_options : nullptr;
  return detect::make_detector(config.detector, signals, hop_seconds, options);
}

std::string yaml_text(const std::optional<config::ConfigNode>& node) {
  if (!node) return {};
  YAML::Emitter out;
  out << node->yaml();
  return out.c_str();
}

}  // namespace

ActuatorMonitor::ActuatorMonitor(const ActuatorConfig& config, const ChannelLayout& layout,
                                 std::int64_t period_ns)
    : config_(config),
      layout_(layout),
      features_(config.features, layout.p2 >= 0 ? 2 : 1),
      detector_(build_detector(config, layout, period_ns)),
      alarm_(effective(config.alarm)),
      fingerprint_(state_fingerprint(config, period_ns)),
      activity_(config.features.window, kNaN),
      index_input_(layout.p2 >= 0 ? 2 : 1, kNaN) {}

AlarmSettings ActuatorMonitor::effective(const AlarmSettings& configured) const {
  AlarmSettings settings = configured;
  if (std::isnan(settings.raise_threshold)) settings.raise_threshold = detector_->raise_threshold();
  if (std::isnan(settings.clear_threshold)) settings.clear_threshold = detector_->clear_threshold();
  return settings;
}

void ActuatorMonitor::set_alarm_settings(const AlarmSettings& settings) {
  config_.alarm = settings;
  alarm_.set_settings(effective(settings));
}

bool ActuatorMonitor::same_pipeline(const ActuatorConfig& other,
                                    const ChannelLayout& other_layout) const {
  const auto& a = config_.features;
  const auto& b = other.features;
  return layout_.p1 == other_layout.p1 && layout_.p2 == other_layout.p2 &&
         layout_.u == other_layout.u && layout_.x == other_layout.x &&
         layout_.xref == other_layout.xref && a.wavelet == b.wavelet && a.level == b.level &&
         a.window == b.window && a.step == b.step && a.mode == b.mode &&
         config_.detector == other.detector &&
         yaml_text(config_.detector_options) == yaml_text(other.detector_options);
}

bool ActuatorMonitor::push(const Sample& sample, const EventPublisher& publish) {
  const double p1 = value_at(sample, layout_.p1);
  const double p2 = value_at(sample, layout_.p2);
  index_input_[0] = p1;
  if (index_input_.size() > 1) index_input_[1] = p2;
  if (std::isnan(p1)) ++gap_samples_;

  if (hop_samples_ >= config_.features.step) {
    hop_u_ = hop_x_ = hop_p1_ = hop_p2_ = HopMean{};
    hop_samples_ = 0;
  }
  hop_u_.add(value_at(sample, layout_.u));
  hop_x_.add(value_at(sample, layout_.x));
  hop_p1_.add(p1);
  hop_p2_.add(p2);
  ++hop_samples_;

  const int activity_channel = layout_.xref >= 0 ? layout_.xref : layout_.x;
  activity_[activity_next_] = value_at(sample, activity_channel);
  activity_next_ = (activity_next_ + 1) % activity_.size();
  if (activity_filled_ < activity_.size()) ++activity_filled_;

  if (!features_.push(index_input_)) return false;
  decide(sample.t, publish);
  return true;
}

void ActuatorMonitor::push_gap(double t, const EventPublisher& publish) {
  Sample gap;
  gap.t = t;
  gap.values.fill(kNaN);
  push(gap, publish);
}

void ActuatorMonitor::decide(double t, const EventPublisher& publish) {
  detect::Observation observation;
  observation.t = t;
  const auto latest = features_.latest();
  observation.index_p1 = latest[0].valid ? latest[0].rms : kNaN;
  if (latest.size() > 1) observation.index_p2 = latest[1].valid ? latest[1].rms : kNaN;
  auto mean = [&](const HopMean& hop, int channel) {
    if (channel < 0 || hop.gap || hop_samples_ == 0) return kNaN;
    return hop.sum / static_cast<double>(hop_samples_);
  };
  observation.u = mean(hop_u_, layout_.u);
  observation.x = mean(hop_x_, layout_.x);
  observation.p1 = mean(hop_p1_, layout_.p1);
  observation.p2 = mean(hop_p2_, layout_.p2);
  if ((layout_.xref >= 0 || layout_.x >= 0) && activity_filled_ == activity_.size()) {
    double sum = 0.0;
    for (double v : activity_) sum += v;
    const double m = sum / static_cast<double>(activity_.size());
    double squares = 0.0;
    for (double v : activity_) squares += (v - m) * (v - m);
    observation.x_activity = std::sqrt(squares / static_cast<double>(activity_.size()));
  }
  hop_u_ = hop_x_ = hop_p1_ = hop_p2_ = HopMean{};
  hop_samples_ = 0;

  last_decision_ = detector_->update(observation);
  last_t_ = t;
  last_load_pressure_ = std::abs(observation.p1 - observation.p2);
  ++decisions_;

  const AlarmTransition transition = alarm_.update(last_decision_.score, t);
  if (transition.raised) publish(alarm_event(EventKind::alarm_raised, t));
  if (transition.cleared) publish(alarm_event(EventKind::alarm_cleared, t));
}

void ActuatorMonitor::acknowledge(const EventPublisher& publish) {
  const AlarmTransition transition = alarm_.acknowledge();
  if (transition.acknowledged) publish(alarm_event(EventKind::alarm_acknowledged, last_t_));
  if (transition.cleared) publish(alarm_event(EventKind::alarm_cleared, last_t_));
}

Event ActuatorMonitor::alarm_event(EventKind kind, double t) const {
  Event event;
  event.kind = kind;
  event.t = t;
  event.actuator = config_.name;
  event.alarm = config_.alarm_name;
  event.channel = "p1";
  event.index = std::isnan(last_decision_.index) ? features_.latest()[0].rms : last_decision_.index;
  event.score = last_decision_.score;
  event.baseline = last_decision_.baseline;
  event.latched = alarm_.settings().latching && alarm_.active();
  const double c = last_decision_.leak_coefficient;
  if (std::isfinite(c)) {
    event.leak_coefficient = c;
    event.leak_lpm_per_mpa = c * kLpmPerM3s * 1e6;
    event.load_pressure = last_load_pressure_;
    event.leak_lpm = c * last_load_pressure_ * kLpmPerM3s;
    const double half_width = last_decision_.leak_coefficient_ci;
    if (std::isfinite(half_width)) {
      event.leak_lpm_per_mpa_ci95 = half_width * kLpmPerM3s * 1e6;
      event.leak_lpm_ci95 = half_width * last_load_pressure_ * kLpmPerM3s;
    }
  }
  return event;
}

ActuatorState ActuatorMonitor::export_state() const {
  ActuatorState state;
  state.actuator = config_.name;
  state.fingerprint = fingerprint_;
  state.saved_unix =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  state.alarm = alarm_.state();
  state.alarm_condition = alarm_.condition();
  state.detector = detector_->export_state();
  return state;
}

void ActuatorMonitor::import_state(const ActuatorState& state) {
  try {
    detector_->import_state(state.detector);
  } catch (const detect::StateError&) {
    detector_->reset();
    throw;
  }
  alarm_.restore(state.alarm, state.alarm_condition);
  detect::Observation gap;
  last_decision_ = detector_->update(gap);
  last_decision_.score = kNaN;
}

ActuatorStatus ActuatorMonitor::status() const {
  ActuatorStatus status;
  status.name = config_.name;
  status.alarm = config_.alarm_name;
  status.detector = std::string(detector_->name());
  status.state = alarm_.state();
  status.learning = last_decision_.learning;
  status.t = last_t_;
  const auto latest = features_.latest();
  status.index_p1 = latest.empty() ? kNaN : latest[0].rms;
  status.index_p2 = latest.size() > 1 ? latest[1].rms : kNaN;
  status.score = last_decision_.score;
  status.baseline = last_decision_.baseline;
  status.leak_coefficient = last_decision_.leak_coefficient;
  status.decisions = decisions_;
  status.gap_samples = gap_samples_;
  return status;
}

}  // namespace leakmon::daemon
