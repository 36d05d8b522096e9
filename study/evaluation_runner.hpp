// Runs the evaluation's cases: each RunSpec simulated (sim/) and replayed in process through
// exactly the daemon's pipeline (pipeline::replay_capture), every candidate at every threshold
// one actuator of the replayed configuration, so one replay yields the whole ROC sweep.
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <vector>

#include "capture/capture.hpp"
#include "config/yaml_reader.hpp"
#include "pipeline/config.hpp"
#include "study/case_generation.hpp"
#include "study/evaluation_options.hpp"
#include "study/parallel_runs.hpp"

namespace leakmon::study {

struct Alarm {
  double raised = 0.0;
  double leak_coefficient = NAN;
};

// The leak size and its 95 % interval that the flow balance reports when it first raises after
// the onset, at its own threshold.
struct SizeCheck {
  double t = NAN;
  double leak_coefficient = NAN;
  double half_width = NAN;
  bool covers(double truth) const { return std::abs(leak_coefficient - truth) <= half_width; }
};

// A sensor_fault alarm raised in the run (the daemon's default actuator at its design threshold).
struct SensorAlarm {
  double t = NAN;
  std::string channel, fault;
};
// The candidate whose sensor_fault alarms a run records: "default".
inline constexpr std::size_t kSensorCandidate = 5;

// One run's record.
struct RunResult {
  RunSpec spec;
  SizeCheck size_check;
  // [candidate][threshold] -> raise times and sizes
  std::vector<std::vector<std::vector<Alarm>>> alarms;
  double seconds = 0.0;
  std::vector<SensorAlarm> sensor_alarms;
  // restart runs: actuators that resumed their saved state at the restart (0: none did).
  int states_restored = 0;
};

// The learning and settling periods every candidate's detector is configured with.
config::ConfigNode detector_options(const EvaluationOptions& options);

// The daemon configuration that replays `capture`: one actuator per candidate and threshold.
pipeline::DaemonConfig evaluation_config(const capture::Capture& capture,
                                         const EvaluationOptions& options);

// Simulates and replays one run (and writes its capture when options.keep_captures names it).
RunResult evaluate_run(const RunSpec& spec, const EvaluationOptions& options);

// Every run on options.jobs threads; results in the order of `runs`. The first run that throws
// stops the others and is rethrown as std::runtime_error("run ID: what").
std::vector<RunResult> run_evaluation(const std::vector<RunSpec>& runs,
                                      const EvaluationOptions& options,
                                      const Progress& progress = {});

}  // namespace leakmon::study
