// The Monte-Carlo evaluation's settings (`leakmon evaluate`, docs/detection.md) and the
// detectors it compares: each candidate is one replayed actuator per swept alarm threshold.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::study {

struct EvaluationOptions {
  int healthy_runs = 8;
  double healthy_seconds = 900.0;
  int runs_per_leak = 6;
  std::vector<double> leak_sizes = {1e-13, 2.5e-13, 5e-13, 1e-12, 2e-12, 5e-12};
  double learn_seconds = 90.0;
  double settle_seconds = 2.0;
  double after_onset_seconds = 90.0;
  double detect_within = 60.0;
  std::uint64_t seed = 1;
  int jobs = 2;
  std::vector<std::string> effects;  // MODEL.md effect names on every run (default parameters)
  // Operating conditions the runs are drawn under, in turn (kConditionNames; "stationary" is
  // MODEL.md's stationary rig at 40 degC). Runs under any other condition record `temp` and
  // `ps`, and candidates choose whether to use them.
  std::vector<std::string> conditions = {"stationary"};
  // Runs dedicated to sensor faults (scored per fault kind): a fault after learning, a leak
  // opening during it in every second run, and this long after the fault.
  int sensor_fault_runs = 0;
  double after_fault_seconds = 90.0;
  // restart: how long the daemon watches a healthy rig after restarting.
  double after_restart_seconds = 300.0;
  // programs and wear: phase lengths and wear durations are MODEL.md's typical values times this
  // (1; smaller for a quick check).
  double time_scale = 1.0;
  // "paper": rigs across MODEL.md's calibration spread of the paper's rig; "other": each run on
  // a rig drawn by sim::draw_other_rig, leaks scaled to its valve (study/rig_cases.hpp).
  std::string rigs = "paper";
  std::vector<int> keep_captures;  // run ids whose capture CSV is written into `out`
  std::filesystem::path out;
};

// A detector as the daemon would be configured with it: which channels the actuator acquires,
// the detector kind, and the alarm thresholds swept for its ROC curve (the design point first).
struct Candidate {
  std::string label;  // as in the outputs
  std::string kind;   // detect::make_detector kind
  bool p2, u, x;      // channels besides p1
  std::vector<double> raise_thresholds;
  double design_threshold;
  double clear_gap;  // clear = raise * clear_ratio (or raise - clear_gap when > 0)
  double clear_ratio;
  bool temp = false;  // also the oil temperature channel, where the capture has one
};

std::vector<Candidate> candidates();

// The conditions `--conditions` takes: stationary, warmup (a morning warm-up from 15-35 degC to
// 45-55 degC, time constant 5-20 min, learning during it), cooler (a warm rig cycling +-1-4 K
// every 5-20 min), supply (one or two set-point changes to 13-20 MPa), sensor-faults (one fault
// of one transducer: frozen, saturated, spikes or dropout, 10-60 s), restart (the daemon stopped
// after learning and restarted from its saved state after a downtime of 10 s-30 min in which
// the oil warmed or cooled by 1-5 K and, in leak runs, the leak opened), each with an oil grade
// VG 32, 46 or 68; programs (MODEL.md "Test programs": 3-8 phases of steps, hold, sine, sweep
// and triangle with its typical values and lengths, half of them starting with a hold; healthy
// runs last as long as their program, leak runs open their leak inside a phase of a given kind;
// the stationary rig) and wear (C_L growing linearly from 0 to 1e-12..5e-12 over 10 min to 4 h
// on the paper's steps, the oil cycling with the cooler as under `cooler`; healthy runs: the
// same rig without wear).
inline constexpr std::string_view kConditionNames[] = {
    "stationary", "warmup", "cooler", "supply", "sensor-faults", "restart", "programs", "wear"};
bool is_condition(std::string_view name);

// Position of the design threshold in `raise_thresholds` (its size when absent).
std::size_t design_index(const Candidate& candidate);

// The replayed actuator's name for candidate c at threshold t.
std::string actuator_name(std::size_t candidate, std::size_t threshold);

}  // namespace leakmon::study
