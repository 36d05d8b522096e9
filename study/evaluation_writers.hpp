// The evaluation's files (docs/detection.md; docs/tools/detection_plots.py and
// detection_tables.py read them): runs.json, summary.json, summary.tsv, summary.md and
// size_coverage.tsv; conditions.md and conditions.tsv, with programs.tsv and wear.tsv when the
// runs have test programs or seals that wear.
#pragma once

#include <filesystem>
#include <vector>

#include "study/evaluation_options.hpp"
#include "study/evaluation_runner.hpp"

namespace leakmon::study {

// Every run with its rig and each candidate's alarms at the design threshold.
void write_runs_json(const std::filesystem::path& path, const std::vector<RunResult>& results);

// summary.json, summary.tsv, summary.md and size_coverage.tsv into `dir`: per candidate, per
// threshold (ROC) and per leak size and controller; the Markdown at the design thresholds.
void write_summaries(const std::filesystem::path& dir, const EvaluationOptions& options,
                     const std::vector<RunResult>& results);

// conditions.md and conditions.tsv into `dir`: per operating condition (options.conditions), each
// candidate's false alarms per healthy hour (count, hours, 95 % upper bound) and detection within
// the window per leak size at its design threshold; for sensor-faults runs, how many faults were
// named on the right channel within 5 s, and any internal_leakage raised while one was present;
// for test programs, the tables per phase kind and by how the program starts (also programs.tsv);
// for seals that wear, the C_L at which they were found (also wear.tsv).
void write_condition_summaries(const std::filesystem::path& dir, const EvaluationOptions& options,
                               const std::vector<RunResult>& results);

}  // namespace leakmon::study
