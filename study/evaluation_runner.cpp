#include "study/evaluation_runner.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>

#include "detect/factory.hpp"
#include "pipeline/replay.hpp"
#include "sim/random.hpp"
#include "sim/sensor_faults.hpp"
#include "sim/simulate.hpp"

namespace leakmon::study {
namespace {

// The alarm events carry the size and its interval too (since commit 8288380), but the
// coverage is measured here, independently of the alarm logic: the flow balance is run once
// more on the capture's hop means (the same Observation fields the worker fills) and its first
// raise at its own threshold within detect_within of the onset is taken.
SizeCheck check_size(const capture::Capture& capture, const RunSpec& spec,
                     const EvaluationOptions& options, const config::ConfigNode& detector_config) {
  constexpr std::size_t kStep = 20;  // the daemon's default hop
  const double hop_seconds = static_cast<double>(kStep) / capture.sample_rate_hz();
  const auto detector = detect::make_detector("flow_balance", {true, true, true, true}, hop_seconds,
                                              &detector_config);
  const auto& t = capture.column("t");
  const auto &u = capture.column("u"), &x = capture.column("x");
  const auto &p1 = capture.column("p1"), &p2 = capture.column("p2");
  auto mean = [](const std::vector<double>& v, std::size_t from, std::size_t to) {
    double sum = 0.0;
    for (std::size_t i = from; i < to; ++i) sum += v[i];
    return sum / static_cast<double>(to - from);
  };
  SizeCheck check;
  for (std::size_t end = kStep; end <= capture.rows(); end += kStep) {
    detect::Observation o;
    o.t = t[end - 1];
    o.u = mean(u, end - kStep, end);
    o.x = mean(x, end - kStep, end);
    o.p1 = mean(p1, end - kStep, end);
    o.p2 = mean(p2, end - kStep, end);
    const detect::Decision decision = detector->update(o);
    if (o.t < spec.onset || !(decision.score >= detector->raise_threshold())) continue;
    if (o.t - spec.onset > options.detect_within) break;
    check = {o.t, decision.leak_coefficient, decision.leak_coefficient_ci};
    break;
  }
  return check;
}

// When a spikes fault first shows: the first sample the injected spikes change. The fault's
// random stream is replayed on constant readings (it draws the same numbers whatever the
// readings are), so the plant need not be simulated again.
double first_spike(const sim::Scenario& scenario) {
  for (const sim::SensorFault& fault : scenario.faults) {
    if (fault.kind != sim::SensorFault::Kind::spikes) continue;
    sim::SensorFaults faults(scenario.faults, scenario.sensors, 0.5 * scenario.params.L,
                             sim::stream_seed(scenario.seed, sim::RandomStream::sensor_faults));
    const double period = 1.0 / scenario.sample_rate_hz;
    const sim::Readings steady{10e6, 10e6, 0.0, 17e6, 40.0};
    const double end = std::min(fault.start_s + fault.duration_s, scenario.duration_s);
    for (auto k = static_cast<std::int64_t>(std::max(0.0, fault.start_s / period - 1.0));; ++k) {
      const double t = static_cast<double>(k) * period;
      if (t >= end) break;
      sim::Readings r = steady;
      faults.apply(t, period, r);
      if (r[fault.channel] != sim::Readings(steady)[fault.channel]) return t;
    }
    return NAN;  // no spike came in the fault's time
  }
  return NAN;
}

// Alarms of one replay into `result`, their times shifted by `offset` (a restarted replay's
// clock starts at the restart).
void collect_alarms(const pipeline::ReplayResult& replay, double offset, RunResult& result) {
  const auto all = candidates();
  std::map<std::string, std::pair<std::size_t, std::size_t>> by_name;
  for (std::size_t c = 0; c < all.size(); ++c) {
    for (std::size_t t = 0; t < all[c].raise_thresholds.size(); ++t) {
      by_name[actuator_name(c, t)] = {c, t};
    }
  }
  const std::string sensor_actuator =
      actuator_name(kSensorCandidate, design_index(all[kSensorCandidate]));
  for (const auto& event : replay.events) {
    if (event.kind == io::EventKind::state_restored) ++result.states_restored;
    if (event.kind != io::EventKind::alarm_raised) continue;
    if (event.alarm == "sensor_fault") {
      if (event.actuator == sensor_actuator)
        result.sensor_alarms.push_back({event.t + offset, event.channel, event.fault});
      continue;
    }
    const auto found = by_name.find(event.actuator);
    if (found == by_name.end()) continue;
    result.alarms[found->second.first][found->second.second].push_back(
        {event.t + offset, event.leak_coefficient});
  }
}

// A directory of its own for one run's saved state (several runs replay at once).
std::filesystem::path state_directory(const RunSpec& spec) {
  return std::filesystem::temp_directory_path() /
         fmt::format("leakmon-evaluate-{}-{}-{}", ::getpid(), spec.id, spec.scenario.seed);
}

}  // namespace

config::ConfigNode detector_options(const EvaluationOptions& options) {
  return config::ConfigNode::load_string(fmt::format("learn_seconds: {}\nsettle_seconds: {}\n",
                                                     options.learn_seconds, options.settle_seconds),
                                         "leakmon evaluate");
}

pipeline::DaemonConfig evaluation_config(const capture::Capture& capture,
                                         const EvaluationOptions& options) {
  pipeline::DaemonConfig config = pipeline::default_replay_config(capture);
  const pipeline::ActuatorConfig base = config.actuators.at(0);
  config.actuators.clear();
  const auto detector_config = detector_options(options);
  const auto all = candidates();
  for (std::size_t c = 0; c < all.size(); ++c) {
    const Candidate& candidate = all[c];
    for (std::size_t t = 0; t < candidate.raise_thresholds.size(); ++t) {
      pipeline::ActuatorConfig a = base;
      a.name = actuator_name(c, t);
      a.detector = candidate.kind;
      a.detector_options = detector_config;
      if (!candidate.p2) a.channels[capture::Role::p2] = {};
      if (!candidate.u) a.channels[capture::Role::u] = {};
      if (!candidate.x) a.channels[capture::Role::x] = {};
      if (!candidate.temp) a.channels[capture::Role::temp] = {};
      a.channels[capture::Role::ps] =
          {};  // the detectors read the supply from the chamber pressures at rest
      const double raise = candidate.raise_thresholds[t];
      a.alarm.raise_threshold = raise;
      a.alarm.clear_threshold =
          candidate.clear_gap > 0.0 ? raise - candidate.clear_gap : raise * candidate.clear_ratio;
      config.actuators.push_back(std::move(a));
    }
  }
  return config;
}

RunResult evaluate_run(const RunSpec& spec, const EvaluationOptions& options) {
  RunResult result;
  result.spec = spec;
  const auto all = candidates();
  result.alarms.resize(all.size());
  for (std::size_t c = 0; c < all.size(); ++c)
    result.alarms[c].resize(all[c].raise_thresholds.size());
  if (spec.fault_kind == "spikes") result.spec.fault_seen = first_spike(spec.scenario);

  const capture::Capture capture = sim::simulate(spec.scenario);
  if (std::find(options.keep_captures.begin(), options.keep_captures.end(), spec.id) !=
      options.keep_captures.end()) {
    capture::write_capture((options.out / fmt::format("run-{}.csv", spec.id)).string(), capture);
  }
  if (!spec.after_restart) {
    collect_alarms(pipeline::replay_capture(capture, evaluation_config(capture, options)), 0.0,
                   result);
    if (spec.leak > 0.0 && !spec.wear_run()) {
      result.size_check = check_size(capture, spec, options, detector_options(options));
    }
    result.seconds = spec.scenario.duration_s;
    return result;
  }

  // A restart: the first capture replayed as the daemon ran until it stopped (saving its state
  // at the end, as at shutdown), the second as the daemon started again on that state.
  const std::filesystem::path directory = state_directory(spec);
  std::filesystem::remove_all(directory);
  pipeline::ReplayOptions replay_options;
  replay_options.state_directory = directory.string();
  try {
    collect_alarms(
        pipeline::replay_capture(capture, evaluation_config(capture, options), replay_options), 0.0,
        result);
    const capture::Capture after = sim::simulate(*spec.after_restart);
    if (std::find(options.keep_captures.begin(), options.keep_captures.end(), spec.id) !=
        options.keep_captures.end()) {
      capture::write_capture((options.out / fmt::format("run-{}-restarted.csv", spec.id)).string(),
                             after);
    }
    collect_alarms(
        pipeline::replay_capture(after, evaluation_config(after, options), replay_options),
        spec.restart_at, result);
    result.seconds = spec.restart_at + spec.after_restart->duration_s;
  } catch (...) {
    std::filesystem::remove_all(directory);
    throw;
  }
  std::filesystem::remove_all(directory);
  return result;
}

std::vector<RunResult> run_evaluation(const std::vector<RunSpec>& runs,
                                      const EvaluationOptions& options, const Progress& progress) {
  return run_in_parallel<RunResult>(runs, options.jobs, progress,
                                    [&](const RunSpec& run) { return evaluate_run(run, options); });
}

}  // namespace leakmon::study
