// Detection on rigs other than the paper's (`leakmon evaluate --rigs other`, docs/detection.md
// "Other rigs"). Each run's rig is drawn by sim::draw_other_rig (MODEL.md "Other rigs": bore,
// supply, valve, mass, load, volumes, oil, with a step amplitude and transducers that fit it),
// its leak sized relative to the valve (C_L = size x Kv / 3.39e-7: the same share of the
// valve's flow as `size` on the paper's rig), and replayed through the daemon's pipeline with
// the default detector for three sets of channels, each once told the rig (the actuator's
// `rig:`) and once not (the paper's defaults). Both classes are configured with the rig's
// transducers: what differs is only whether the detector knows the rig.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "capture/capture.hpp"
#include "pipeline/config.hpp"
#include "study/case_generation.hpp"
#include "study/evaluation_options.hpp"
#include "study/evaluation_runner.hpp"
#include "study/evaluation_summary.hpp"

namespace leakmon::study {

// The leak size the run's condition names, before scaling to the valve (0 for a healthy run).
double paper_equivalent_leak(const RunSpec& run);

// A detector configuration compared on other rigs: the default detector on some channels.
struct RigCandidate {
  std::string label;  // the channels, e.g. "p1,p2,u,x"
  bool p2, u, x;
  bool told;  // the actuator carries the rig's description (`rig:`)
};
std::vector<RigCandidate> rig_candidates();

// The replay configuration: one actuator per rig candidate ("r0", "r1", ...) at its detector's
// own thresholds, transducers as the run's (range, resolution, noise), `rig:` for the told ones.
pipeline::DaemonConfig rig_evaluation_config(const capture::Capture& capture, const RunSpec& run,
                                             const EvaluationOptions& options);

// The load pressure the spring holds at rest at the steps' mean amplitude, K_s a / A [Pa]: what a
// leak flows on while the flow balance judges it. MODEL.md ("Test programs"): below about 1 MPa a
// leak's flow is too small to see in any channel; a rig without a spring has none at all.
double rest_load_pressure(const sim::Scenario& scenario);
inline constexpr double kSeeableRestLoad = 1e6;  // [Pa]

struct RigRunResult {
  // alarms[candidate][0]: the internal_leakage raises of each rig candidate (add_run's layout).
  RunResult run;
  double mode_hz = 0.0;         // sim::hydraulic_mode_hz of the simulated plant
  bool mode_in_band = false;    // within pipeline::ModeVisibilityCheck::readable_band at 500 Hz
  double rest_load = 0.0;       // rest_load_pressure [Pa]
  std::vector<bool> blind;      // per candidate: it announced detection_blind
  std::vector<bool> any_fault;  // per candidate: it raised a sensor_fault alarm
  std::string first_fault;      // the first sensor_fault alarm's channel and kind, e.g. "p1 spikes"
};

RigRunResult evaluate_rig_run(const RunSpec& spec, const EvaluationOptions& options);

// Every run on options.jobs threads, results in the order of `runs` (as run_evaluation).
std::vector<RigRunResult> run_rig_evaluation(const std::vector<RunSpec>& runs,
                                             const EvaluationOptions& options,
                                             const Progress& progress = {});

// One candidate's scores: false alarms over every run's healthy time, leaks per
// paper-equivalent size found within the window, sizes; for pressure-only candidates also how
// the detection_blind verdict fell on rigs whose mode is out of the index's band.
struct RigScore {
  Rates all;                    // healthy time of every run, every leak run
  std::vector<Rates> per_size;  // per options.leak_sizes, in order
  Rates not_blind;              // leak runs on rigs the candidate did not call blind
  Rates loaded;                 // leak runs on rigs whose rest load reaches kSeeableRestLoad
  int out_of_band_runs = 0, out_of_band_blind = 0;
  int in_band_runs = 0, in_band_blind = 0;
  int sensor_fault_runs = 0;  // runs with a sensor_fault alarm (no fault was injected)
};
RigScore score_rig_candidate(const std::vector<RigRunResult>& results, std::size_t candidate,
                             const EvaluationOptions& options);

// rigs.md (the per-class table and the rigs drawn), rigs.tsv (one row per candidate) and
// rigs_runs.tsv (one row per run: its rig, mode, leak and each candidate's first raise).
void write_rig_summaries(const std::filesystem::path& dir, const EvaluationOptions& options,
                         const std::vector<RigRunResult>& results);

}  // namespace leakmon::study
