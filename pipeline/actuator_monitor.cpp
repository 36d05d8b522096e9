#include "pipeline/actuator_monitor.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <tuple>

#include "capture/units.hpp"
#include "detect/factory.hpp"
#include "sim/rig_draw.hpp"

namespace leakmon::pipeline {
namespace {

using capture::Role;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double value_at(const realtime::Sample& sample, int index) {
  return index < 0 ? kNaN : sample.values[static_cast<std::size_t>(index)];
}

std::unique_ptr<detect::Detector> build_detector(const ActuatorConfig& config,
                                                 const ChannelLayout& layout,
                                                 std::int64_t period_ns) {
  const detect::AvailableSignals signals = available_signals(layout.acquired());
  const double hop_seconds =
      static_cast<double>(config.features.step) * static_cast<double>(period_ns) / 1e9;
  const config::ConfigNode* options = config.detector_options ? &*config.detector_options : nullptr;
  return detect::make_detector(config.detector, signals, hop_seconds, options, &config.rig);
}

// Learning hops the mode verdict needs at least (1 s at the default hop of 40 ms); with fewer the
// rig stays unjudged.
constexpr std::size_t kModeJudgedHops = 25;
// A pressure-only detector's index below this share of the learning period's median reads no
// hydraulic mode (a hold); a leak of interest lowers it by a few percent, the largest by a third.
constexpr double kNoExcitationShare = 0.5;

// The mode of a rig that `rig:` describes; NaN for the paper's (nothing stated).
double rig_mode_hz(const sim::RigDescription& rig) {
  if (rig.nominal()) return kNaN;
  return sim::hydraulic_mode_hz(rig.params);
}

ModeVisibilityCheck mode_check(const detect::TransducerSpec& spec) {
  return ModeVisibilityCheck(
      ModeVisibilityCheck::noise_floor_pa(spec.noise_sigma, spec.resolution));
}

}  // namespace

capture::ByRole<bool> ChannelLayout::acquired() const {
  capture::ByRole<bool> roles;
  for (const Role role : capture::kRoles) roles[role] = index[role] >= 0;
  return roles;
}

ActuatorMonitor::ActuatorMonitor(const ActuatorConfig& config, const ChannelLayout& layout,
                                 std::int64_t period_ns)
    : config_(config),
      layout_(layout),
      features_(config.features, layout[Role::p2] >= 0 ? 2 : 1),
      detector_(build_detector(config, layout, period_ns)),
      alarm_(effective(config.alarm)),
      fingerprint_(state_fingerprint(config, period_ns)),
      hop_samples_p1_(config.features.step, kNaN),
      hop_samples_p2_(config.features.step, kNaN),
      hop_samples_u_(config.features.step, kNaN),
      hop_samples_x_(config.features.step, kNaN),
      activity_(config.features.window, kNaN),
      index_input_(layout[Role::p2] >= 0 ? 2 : 1, kNaN),
      sample_rate_hz_(1e9 / static_cast<double>(period_ns)),
      watch_mode_(detector_->needs_hydraulic_mode()),
      mode_checks_{mode_check(config.transducers[Role::p1]),
                   mode_check(config.transducers[Role::p2])},
      rig_mode_hz_(rig_mode_hz(config.rig)),
      mode_out_of_band_([&] {
        const auto band = ModeVisibilityCheck::readable_band(1e9 / static_cast<double>(period_ns),
                                                             config.features.level);
        return rig_mode_hz_ < band.low || rig_mode_hz_ > band.high;
      }()),
      period_ns_(period_ns) {
  const double rate = sample_rate_hz_;
  channels_.reserve(3);
  for (const Role role : kCheckedRoles) {
    if (layout[role] < 0) continue;
    check_slot_[role] = static_cast<int>(channels_.size());
    channels_.push_back(
        Channel{role, layout[role], detect::SensorPlausibility(config.transducers[role], rate)});
  }
  if (watch_mode_) {
    const double hop_s = static_cast<double>(config.features.step) / rate;
    index_probes_.reserve(2);
    index_probes_.emplace_back("p1", learning_seconds(), hop_s);
    if (layout[Role::p2] >= 0) index_probes_.emplace_back("p2", learning_seconds(), hop_s);
  }
}

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

void ActuatorMonitor::set_transducers(const ActuatorConfig& config) {
  config_.transducers = config.transducers;
  for (auto& channel : channels_) {
    channel.check.reconfigure(config_.transducers[channel.role], sample_rate_hz_);
  }
}

bool ActuatorMonitor::same_pipeline(const ActuatorConfig& other,
                                    const ChannelLayout& other_layout) const {
  return layout_ == other_layout && fingerprint_ == state_fingerprint(other, period_ns_);
}

std::string ActuatorMonitor::fingerprint_change(const StateFingerprint& other) const {
  std::string change;
  for (const auto& [name, value] : other.parts) {
    std::string before = "(none)";
    for (const auto& [old_name, old_value] : fingerprint_.parts) {
      if (old_name == name) before = old_value;
    }
    if (before == value) continue;
    if (!change.empty()) change += "; ";
    change += fmt::format("{}: {} -> {}", name, before.empty() ? "(none)" : before,
                          value.empty() ? "(none)" : value);
  }
  return change.empty() ? "channel layout" : change;
}

double ActuatorMonitor::learning_seconds() const {
  const double window_s = static_cast<double>(config_.features.window) / sample_rate_hz_;
  return window_s + detector_->learning_seconds();
}

void ActuatorMonitor::note_relearning(std::uint64_t relearns, double protected_from) {
  relearns_ = relearns;
  protected_from_ = protected_from;
}

bool ActuatorMonitor::push(const realtime::Sample& sample, const EventPublisher& publish) {
  // Every checked channel releases its cleaned value of kDelay samples ago; u, xref and t wait
  // in delay_ for as long.
  constexpr std::size_t kDelay = detect::SensorPlausibility::kDelay;
  double cleaned[3] = {kNaN, kNaN, kNaN};
  bool suspect = false;
  bool all_missing = !channels_.empty();
  std::array<double, RepeatedSampleCheck::kMaxChannels> acquired{};
  std::size_t acquired_channels = 0;
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    auto& channel = channels_[i];
    const double raw = value_at(sample, channel.index);
    all_missing = all_missing && std::isnan(raw);
    cleaned[i] = channel.check.push(raw);
    suspect |= channel.check.suspect();
    // A channel its own check calls faulty (frozen, saturated: constant by its fault) is
    // reported there; a sample with it is no evidence of a repeating acquisition (NaN is never
    // a repeat), and the leak decision is held for the fault anyway.
    acquired[acquired_channels++] = channel.check.fault() == detect::SensorFault::none ? raw : kNaN;
  }
  if (layout_[Role::u] >= 0) acquired[acquired_channels++] = value_at(sample, layout_[Role::u]);
  suspect |= check_repeats(sample.t, {acquired.data(), acquired_channels}, publish);
  check_sensor_faults(sample.t, all_missing, publish);
  if (std::isnan(protected_from_) && !std::isnan(sample.t)) {
    protected_from_ = sample.t + learning_seconds();
  }
  if (!std::isnan(sample.t)) newest_t_ = sample.t;
  delay_[arrived_ % delay_.size()] = {
      sample.t, value_at(sample, layout_[Role::u]), value_at(sample, layout_[Role::xref]),
      value_at(sample, layout_[Role::ps]), value_at(sample, layout_[Role::temp])};
  ++arrived_;
  if (arrived_ <= kDelay) return false;
  const Unchecked& unchecked = delay_[(arrived_ - 1 - kDelay) % delay_.size()];
  ++fed_;
  // A suspect channel's samples leave the features' window only a window and a hop later.
  if (suspect) blocked_until_ = fed_ + config_.features.window + config_.features.step;

  auto checked = [&](int slot) { return slot < 0 ? kNaN : cleaned[slot]; };
  const double p1 = checked(check_slot_[Role::p1]);
  const double p2 = checked(check_slot_[Role::p2]);
  const double x = checked(check_slot_[Role::x]);
  index_input_[0] = p1;
  if (index_input_.size() > 1) index_input_[1] = p2;
  if (std::isnan(p1)) ++gap_samples_;

  if (hop_samples_ >= config_.features.step) {
    hop_u_ = hop_x_ = hop_p1_ = hop_p2_ = hop_ps_ = hop_temp_ = HopMean{};
    hop_samples_ = 0;
  }
  hop_u_.add(unchecked.u);
  hop_x_.add(x);
  hop_p1_.add(p1);
  hop_p2_.add(p2);
  hop_ps_.add(unchecked.ps);
  hop_temp_.add(unchecked.temp);
  if (hop_samples_ < hop_samples_p1_.size()) {
    hop_samples_p1_[hop_samples_] = p1;
    hop_samples_p2_[hop_samples_] = p2;
    hop_samples_u_[hop_samples_] = unchecked.u;
    hop_samples_x_[hop_samples_] = x;
  }
  ++hop_samples_;

  activity_[activity_next_] = layout_[Role::xref] >= 0 ? unchecked.xref : x;
  activity_next_ = (activity_next_ + 1) % activity_.size();
  if (activity_filled_ < activity_.size()) ++activity_filled_;

  if (!features_.push(index_input_)) return false;
  decide(unchecked.t, publish);
  return true;
}

bool ActuatorMonitor::check_repeats(double t, std::span<const double> acquired,
                                    const EventPublisher& publish) {
  const bool was_repeating = repeats_.repeating();
  const bool repeating = repeats_.push(acquired);
  if (repeating == was_repeating) return repeating;
  // Not a transducer's fault: the acquisition's, reported like a driver's, with the actuator
  // whose leak decision it holds.
  io::Event event;
  event.t = t;
  event.actuator = config_.name;
  event.kind = repeating ? io::EventKind::driver_fault : io::EventKind::driver_recovered;
  event.message = repeating
                      ? fmt::format(
                            "{}: {} of the last {} samples repeat the one before exactly: the "
                            "acquisition delivers new values slower than it samples (a device "
                            "polled faster than it updates?); the leak decision is held",
                            config_.name, repeats_.repeats(), RepeatedSampleCheck::kWindow)
                      : fmt::format(
                            "{}: samples are new again; the leak decision resumes after a "
                            "window of them",
                            config_.name);
  publish(event);
  return repeating;
}

void ActuatorMonitor::judge_mode_visibility(double t, const detect::Observation& observation,
                                            const EventPublisher& publish) {
  if (!mode_judged_) {
    // A rig whose described mode lies outside the band is blind whatever the index shows: said
    // once the first learning period is over, also when the detector discarded it for want of
    // excitation and keeps learning (it may wait for a program that moves for half an hour).
    const bool period_over =
        !last_decision_.learning ||
        (mode_out_of_band_ &&
         last_decision_.not_judged_reason == detect::NotJudgedReason::waiting_for_excitation);
    if (!period_over) {
      mode_checks_[0].add(observation.index_p1);
      mode_checks_[1].add(observation.index_p2);
      return;
    }
    mode_judged_ = true;
    for (const auto& check : mode_checks_) {
      if (check.count() < kModeJudgedHops) continue;
      const double ratio = check.median_ratio();
      if (!(healthy_index_ratio_ >= ratio)) healthy_index_ratio_ = ratio;
    }
    announce_blind_ = detection_blind();
  }
  if (!announce_blind_) return;
  announce_blind_ = false;
  io::Event event;
  event.kind = io::EventKind::detection_blind;
  event.t = t;
  event.actuator = config_.name;
  event.channel = "p1";
  const double floor = mode_checks_[0].noise_floor();
  event.baseline = healthy_index_ratio_ * floor;
  if (mode_out_of_band_) {
    const auto band = ModeVisibilityCheck::readable_band(sample_rate_hz_, config_.features.level);
    event.message = fmt::format(
        "{}: the rig's hydraulic mode, {:.0f} Hz at mid-stroke from its rig: (bulk modulus, "
        "area, volumes, mass), lies outside the {:.0f}-{:.0f} Hz the level-{} details of the "
        "index read (median index while learning {:.1f} kPa, {:.1f} x the transducer's noise): "
        "the {} detector sees a leak only through that mode, so {} cannot be raised on this "
        "rig; acquire the valve command u and the position x for the flow balance",
        config_.name, rig_mode_hz_, band.low, band.high, config_.features.level,
        event.baseline / 1e3, healthy_index_ratio_, detector_->name(), config_.alarm_name);
    publish(event);
    return;
  }
  event.message = fmt::format(
      "{}: the hydraulic mode hardly shows in the chamber pressures (median index while "
      "learning {:.1f} kPa, {:.1f} x the transducer's noise of {:.1f} kPa; below {:.1f} x no "
      "leak was found): the {} detector sees a leak only through that mode, so {} cannot be "
      "raised on this rig. Seal friction holding the piston at rest, or much free air, does "
      "this; acquire the valve command u and the position x for the flow balance",
      config_.name, event.baseline / 1e3, healthy_index_ratio_, floor / 1e3,
      ModeVisibilityCheck::kBlindRatio, detector_->name(), config_.alarm_name);
  publish(event);
}

void ActuatorMonitor::judge_learned_change(double t, const EventPublisher& publish) {
  std::optional<detect::LearnedChange> change = detector_->learned_change();
  if (!change && probes_from_start_) {
    for (const auto& probe : index_probes_) {
      auto found = probe.judge();
      if (found && (!change || found->z > change->z)) change = found;
    }
  }
  for (auto& probe : index_probes_) probe.clear();
  if (!change) return;
  io::Event event;
  event.kind = io::EventKind::learned_change;
  event.t = t;
  event.actuator = config_.name;
  event.alarm = config_.alarm_name;
  event.channel = std::string(change->channel);
  event.feature = std::string(change->feature);
  event.change_t = change->change_t;
  std::string size;
  if (change->feature == "index") {
    event.baseline = change->reference;
    event.index = change->reference - change->size;
    size = fmt::format("the {} index fell from {:.1f} to {:.1f} kPa and stayed there",
                       change->channel, change->reference / 1e3, event.index / 1e3);
  } else {
    event.leak_coefficient = change->size;
    event.leak_lpm_per_mpa = units::lpm_per_mpa(change->size);
    // flow_law's residual is the valve's flow in any motion; flow_balance's the command at rest.
    size = change->feature == "flow_residual"
               ? fmt::format(
                     "the valve's flow rose with the load as a leak of {:.3f} l/min/MPa "
                     "would make it",
                     event.leak_lpm_per_mpa)
               : fmt::format(
                     "the valve command at rest rose as a leak of {:.3f} l/min/MPa would "
                     "need",
                     event.leak_lpm_per_mpa);
  }
  event.message = fmt::format(
      "{}: learning may have included a leak at t={:.1f} s: {} ({:.0f} x its standard error), "
      "and the {} detector learned that as healthy, so {} will not be raised for it. Check the "
      "rig and let it learn again once it is known to be tight",
      config_.name, change->change_t, size, change->z, detector_->name(), config_.alarm_name);
  publish(event);
}

void ActuatorMonitor::check_sensor_faults(double t, bool outage, const EventPublisher& publish) {
  for (auto& channel : channels_) {
    const detect::SensorFault fault = channel.check.fault();
    // Every channel missing at once is the acquisition (a driver disconnected, missed cycles),
    // not a transducer: the daemon reports it as driver_fault. The leak decision is held all
    // the same; only a transducer's own dropout is a sensor_fault. A dropout that began in an
    // outage stays unannounced until it has cleared, whatever the channel had announced before
    // (spikes from a damaged stream just before a link dies are still not a dead transducer).
    if (fault != detect::SensorFault::dropout) channel.in_outage = false;
    if (outage && fault == detect::SensorFault::dropout &&
        channel.announced != detect::SensorFault::dropout) {
      channel.in_outage = true;
    }
    if (channel.in_outage || fault == channel.announced) continue;
    io::Event event;
    event.t = t;
    event.actuator = config_.name;
    event.alarm = "sensor_fault";
    event.channel = capture::to_string(channel.role);
    if (channel.announced != detect::SensorFault::none) {
      event.kind = io::EventKind::alarm_cleared;
      event.fault = std::string(detect::to_string(channel.announced));
      publish(event);
    }
    if (fault != detect::SensorFault::none) {
      event.kind = io::EventKind::alarm_raised;
      event.fault = std::string(detect::to_string(fault));
      event.message = fmt::format("{} {}: {} ({})", config_.name, capture::to_string(channel.role),
                                  event.fault, io::to_string(detect::device_status(fault)));
      publish(event);
    }
    channel.announced = fault;
  }
}

void ActuatorMonitor::push_gap(double t, const EventPublisher& publish) {
  realtime::Sample gap;
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
  observation.u = mean(hop_u_, layout_[Role::u]);
  observation.x = mean(hop_x_, layout_[Role::x]);
  observation.p1 = mean(hop_p1_, layout_[Role::p1]);
  observation.p2 = mean(hop_p2_, layout_[Role::p2]);
  observation.ps = mean(hop_ps_, layout_[Role::ps]);
  observation.temp = mean(hop_temp_, layout_[Role::temp]);
  const std::size_t kept = std::min(hop_samples_, hop_samples_p1_.size());
  if (layout_[Role::p1] >= 0) observation.p1_samples = {hop_samples_p1_.data(), kept};
  if (layout_[Role::p2] >= 0) observation.p2_samples = {hop_samples_p2_.data(), kept};
  if (layout_[Role::u] >= 0) observation.u_samples = {hop_samples_u_.data(), kept};
  if (layout_[Role::x] >= 0) observation.x_samples = {hop_samples_x_.data(), kept};
  if ((layout_[Role::xref] >= 0 || layout_[Role::x] >= 0) && activity_filled_ == activity_.size()) {
    double sum = 0.0;
    for (double v : activity_) sum += v;
    const double m = sum / static_cast<double>(activity_.size());
    double squares = 0.0;
    for (double v : activity_) squares += (v - m) * (v - m);
    observation.x_activity = std::sqrt(squares / static_cast<double>(activity_.size()));
  }
  hop_u_ = hop_x_ = hop_p1_ = hop_p2_ = hop_ps_ = hop_temp_ = HopMean{};
  hop_samples_ = 0;
  last_t_ = t;
  if (!std::isnan(observation.temp)) last_temperature_ = observation.temp;
  last_p1_ = observation.p1;
  last_p2_ = observation.p2;

  // A faulty or suspect channel: neither decide nor learn; the score and the alarm hold.
  if (fed_ < blocked_until_) {
    ++suspended_decisions_;
    track_judging(t, false, detect::NotJudgedReason::sensor_fault, publish);
    return;
  }
  const bool was_learning = last_decision_.learning;
  last_decision_ = detector_->update(observation);
  if (last_decision_.learning && !index_probes_.empty()) {
    index_probes_[0].add(t, observation.index_p1);
    if (index_probes_.size() > 1) index_probes_[1].add(t, observation.index_p2);
  }
  if (was_learning && !last_decision_.learning) {
    learning_ended_t_ = t;
    judge_learned_change(t, publish);
  }
  last_load_pressure_ = std::abs(observation.p1 - observation.p2);
  ++decisions_;
  if (watch_mode_) judge_mode_visibility(t, observation, publish);
  // A pressure-only detector sees a leak through the hydraulic mode, which a hold leaves
  // unexcited: an index far below the learning period's median is not a reading of it.
  bool judged = last_decision_.judged;
  detect::NotJudgedReason reason = last_decision_.not_judged_reason;
  if (judged && watch_mode_ && std::isfinite(healthy_index_ratio_)) {
    const double learned_index = healthy_index_ratio_ * mode_checks_[0].noise_floor();
    const double index = std::max(std::isnan(observation.index_p1) ? 0.0 : observation.index_p1,
                                  std::isnan(observation.index_p2) ? 0.0 : observation.index_p2);
    if (index < kNoExcitationShare * learned_index) {
      judged = false;
      reason = detect::NotJudgedReason::no_excitation;
    }
  }
  // A pressure-only detector on a rig whose mode does not show reads no leak: its score moves
  // with whatever else the index holds (the program's excitation on a rig ringing at 6-46 Hz),
  // so it neither judges nor raises (the detection_blind event said so once).
  const bool blind = detection_blind();
  if (blind && !last_decision_.learning) {
    judged = false;
    reason = detect::NotJudgedReason::detection_blind;
  }
  track_judging(t, judged, reason, publish);
  if (blind) return;

  const AlarmTransition transition = alarm_.update(last_decision_.score, t);
  if (transition.raised) publish(alarm_event(io::EventKind::alarm_raised, t));
  if (transition.cleared) publish(alarm_event(io::EventKind::alarm_cleared, t));
}

void ActuatorMonitor::track_judging(double t, bool judged, detect::NotJudgedReason reason,
                                    const EventPublisher& publish) {
  const double hop_seconds = static_cast<double>(config_.features.step) / sample_rate_hz_;
  decided_seconds_ += hop_seconds;
  if (judged) judged_seconds_ += hop_seconds;
  if (judged && !judged_ && not_judged_announced_) {
    io::Event event;
    event.kind = io::EventKind::judging_resumed;
    event.t = t;
    event.actuator = config_.name;
    event.alarm = config_.alarm_name;
    event.not_judged_since = not_judged_since_;
    event.message = fmt::format("{}: the {} detector judges again after {:.0f} s", config_.name,
                                detector_->name(), t - not_judged_since_);
    publish(event);
    not_judged_announced_ = false;
  }
  if (!judged && (judged_ || std::isnan(not_judged_since_))) not_judged_since_ = t;
  if (judged) not_judged_since_ = kNaN;
  judged_ = judged;
  not_judged_reason_ = judged ? detect::NotJudgedReason::none : reason;
  if (!judged && !not_judged_announced_ &&
      t - not_judged_since_ >= config_.alarm.not_judged_event_seconds) {
    io::Event event;
    event.kind = io::EventKind::not_judged;
    event.t = t;
    event.actuator = config_.name;
    event.alarm = config_.alarm_name;
    event.reason = std::string(detect::to_string(not_judged_reason_));
    event.not_judged_since = not_judged_since_;
    event.message = fmt::format(
        "{}: the {} detector has not judged for {:.0f} s ({}): a leak opening now would not "
        "raise {}",
        config_.name, detector_->name(), t - not_judged_since_, event.reason, config_.alarm_name);
    publish(event);
    not_judged_announced_ = true;
  }
}

void ActuatorMonitor::acknowledge(const EventPublisher& publish) {
  const AlarmTransition transition = alarm_.acknowledge();
  if (transition.acknowledged) publish(alarm_event(io::EventKind::alarm_acknowledged, last_t_));
  if (transition.cleared) publish(alarm_event(io::EventKind::alarm_cleared, last_t_));
}

io::Event ActuatorMonitor::alarm_event(io::EventKind kind, double t) const {
  io::Event event;
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
    event.leak_lpm_per_mpa = units::lpm_per_mpa(c);
    event.load_pressure = last_load_pressure_;
    // The coefficient is stated at 40 degC when the oil temperature is known; the flow is the
    // one at the present temperature and load.
    const double r =
        std::isfinite(last_decision_.viscosity_ratio) ? last_decision_.viscosity_ratio : 1.0;
    event.leak_lpm = units::litres_per_minute(c * r * last_load_pressure_);
    const double half_width = last_decision_.leak_coefficient_ci;
    if (std::isfinite(half_width)) {
      event.leak_lpm_per_mpa_ci95 = units::lpm_per_mpa(half_width);
      event.leak_lpm_ci95 = units::litres_per_minute(half_width * r * last_load_pressure_);
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
  if (mode_judged_) state.healthy_index_ratio = healthy_index_ratio_;
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
  // The probes would see only the rest of the learning period: no reference to judge it by.
  probes_from_start_ = false;
  detector_->resume_after_gap();
  detect::Observation gap;
  last_decision_ = detector_->update(gap);
  // The verdict of the learning period the state comes from. A detector still learning is
  // judged when it is done; one that has learned without a verdict (a format-1 state) stays
  // unjudged, since later hops may carry a leak.
  healthy_index_ratio_ = state.healthy_index_ratio;
  mode_judged_ = std::isfinite(healthy_index_ratio_) || !last_decision_.learning;
  announce_blind_ = mode_judged_ && detection_blind();
  last_decision_.score = kNaN;
}

ActuatorStatus ActuatorMonitor::status() const {
  ActuatorStatus status;
  status_into(status);
  return status;
}

void ActuatorMonitor::status_into(ActuatorStatus& status) const {
  status.name = config_.name;
  status.alarm = config_.alarm_name;
  status.detector = detector_->name();
  status.state = alarm_.state();
  status.learning = last_decision_.learning;
  status.learning_seconds = learning_seconds();
  status.learning_ended_t = learning_ended_t_;
  status.raise_threshold = alarm_.settings().raise_threshold;
  status.clear_threshold = alarm_.settings().clear_threshold;
  status.t = last_t_;
  const auto latest = features_.latest();
  status.index_p1 = latest.empty() ? kNaN : latest[0].rms;
  status.index_p2 = latest.size() > 1 ? latest[1].rms : kNaN;
  status.score = last_decision_.score;
  status.baseline = last_decision_.baseline;
  status.leak_coefficient = last_decision_.leak_coefficient;
  status.leak_coefficient_ci = last_decision_.leak_coefficient_ci;
  status.oil_temperature = last_temperature_;
  status.p1 = last_p1_;
  status.p2 = last_p2_;
  status.decisions = decisions_;
  status.gap_samples = gap_samples_;
  status.suspended = fed_ < blocked_until_;
  status.repeated_samples = repeats_.repeats();
  status.mode_visibility = watch_mode_ ? healthy_index_ratio_ : io::kNoValue;
  status.detection_blind = detection_blind();
  status.suspended_decisions = suspended_decisions_;
  status.relearns = relearns_;
  status.judged = judged_;
  status.not_judged_reason = not_judged_reason_;
  status.not_judged_since = not_judged_since_;
  status.judged_seconds = judged_seconds_;
  status.decided_seconds = decided_seconds_;
  // The detector counts its own hops (it does not learn while a faulty channel suspends it);
  // before its first decision, and after a reload made it learn again, the protection end
  // the monitor set is what is known.
  if (!status.learning) {
    status.learning_seconds_left = 0.0;
  } else if (!std::isnan(last_decision_.learning_hops_left)) {
    status.learning_seconds_left = last_decision_.learning_hops_left *
                                   static_cast<double>(config_.features.step) / sample_rate_hz_;
  } else if (!std::isnan(protected_from_) && !std::isnan(newest_t_)) {
    status.learning_seconds_left = std::max(0.0, protected_from_ - newest_t_);
  }
  status.channels.resize(channels_.size());
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    const auto& channel = channels_[i];
    auto& out = status.channels[i];
    out.channel = capture::to_string(channel.role);
    out.status = channel.check.status();
    out.fault = channel.check.fault();
    out.spikes_rejected = channel.check.spikes_rejected();
  }
}

}  // namespace leakmon::pipeline
