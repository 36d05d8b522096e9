// The wavelet index on real actuators (`leakmon realdata`, docs/detection.md): for each pair of
// units on the same load, a faulty one and its healthy partner, the separation (AUC) of each
// stroke feature and what the paper's rule "index below the healthy baseline" flags, so that
// one sees whether a leak shows and whether gear damage would be called a leak.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "study/stroke_features.hpp"

namespace leakmon::study {

// One unit's folder in the data set and what is wrong with it.
struct UnitSpec {
  std::string folder, role;
};

struct PairSpec {
  std::string label;
  UnitSpec faulty, healthy;
};

// The vtnsi data set's layout (its README): Act_4 has a leaking inner seal and Act_1 is its
// healthy pair on the same butterfly-valve load; Act_3 has gear damage and Act_2 is its pair
// on a ball-valve load.
std::vector<PairSpec> vtnsi_layout();

struct Unit {
  std::string folder, role;
  std::vector<Stroke> strokes;
};

// Every stroke file of `spec.folder` under `data`, measured, in file-name order.
Unit read_unit(const std::filesystem::path& data, const UnitSpec& spec);

// One feature of a pair: medians of the measured strokes and the AUC.
struct FeatureComparison {
  std::string name;
  double median_faulty = 0.0, median_healthy = 0.0;
  double auc_greater = 0.0;  // P(faulty stroke's value > healthy's), ties half; NaN when empty
  std::size_t n_faulty = 0, n_healthy = 0;
};

struct PairResult {
  std::string label;
  Unit faulty, healthy;
  std::vector<FeatureComparison> features;
  // The paper's rule with a learned baseline: a stroke is "leaking" when its index is below
  // the q-quantile of the healthy pair's strokes.
  double baseline = 0.0;
  double flagged_faulty = 0.0, flagged_healthy = 0.0;  // fractions of strokes
};

struct RealdataResult {
  double baseline_quantile = 0.05;
  std::vector<PairResult> pairs;
};

// Reads every unit of `layout` under `data` (faulty first in each pair) and compares the pairs.
RealdataResult analyse_realdata(const std::filesystem::path& data,
                                const std::vector<PairSpec>& layout, double baseline_quantile);

// P(a faulty stroke's feature > a healthy stroke's), ties counted half: 0.5 = no separation.
double auc_greater(const std::vector<double>& faulty, const std::vector<double>& healthy);

// strokes.csv: one row per stroke of every unit.
void write_strokes_csv(const std::filesystem::path& path, const RealdataResult& result);
void write_realdata_json(const std::filesystem::path& path, const RealdataResult& result);
// The tables of realdata.md (also what the command prints).
std::string realdata_markdown(const RealdataResult& result);

}  // namespace leakmon::study
