// Per-stroke features of the vtnsi real-actuator data set (../shared/data/vtnsi_actuator,
// README there): Moog Flo-Tork rotary actuators, one tab-separated file per stroke. Per stroke:
// the db8 level-2 detail RMS (the paper's index) of the pressurised port over one 400-sample
// window in mid-stroke and one in the hold after it, the stroke's length and the hold's port
// pressure difference.
#pragma once

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace leakmon::study {

struct Stroke {
  std::string file;
  double stroke_index = NAN;  // counts (raw 14-bit ADC)
  double hold_index = NAN;
  double stroke_samples = NAN;
  double hold_load = NAN;  // pressurised minus other port over the hold window [counts]
};

// Raw columns of one stroke file.
struct StrokeSignals {
  std::vector<double> angle, port1, port2;
};

// Columns Angle, PG_1 and PG_2 of a stroke file; throws std::runtime_error naming file, line
// and column on malformed input.
StrokeSignals read_stroke(const std::string& path);

// Finds the stroke (where the angle moves) and measures it; features stay NaN where the file
// is too short for them.
Stroke measure_stroke(const std::string& path);

// The stroke files (*.txt) of one unit's folder, sorted; throws when there are none.
std::vector<std::string> stroke_files(const std::filesystem::path& folder);

}  // namespace leakmon::study
