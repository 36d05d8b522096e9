#include "study/evaluation_options.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace leakmon::study {

std::vector<Candidate> candidates() {
  const std::vector<double> cusum_grid = {0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0};
  return {
      {"paper", "paper", false, false, false, {0.6, 0.7, 0.8, 0.9, 0.95, 0.99}, 0.9, 0.2, 0.0},
      {"index_cusum_p1", "index_cusum", false, false, false, cusum_grid, 1.0, 0.0, 0.5},
      {"index_cusum", "index_cusum", true, false, false, cusum_grid, 1.0, 0.0, 0.5},
      {"flow_balance", "flow_balance", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
      {"fused", "fused", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
      {"default", "default", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
      // The daemon's default with an oil temperature transducer too (drifting conditions).
      {"default_temp", "default", true, true, true, cusum_grid, 1.0, 0.0, 0.5, true},
      {"index_cusum_temp", "index_cusum", true, false, false, cusum_grid, 1.0, 0.0, 0.5, true},
      // Pressure only (issue 13): level-2 detail correlation of p1 and p2; p1 alone: its band
      // ratio against d1 and d3.
      {"detail_xcorr", "detail_xcorr", true, false, false, cusum_grid, 1.0, 0.0, 0.5},
      {"detail_xcorr_p1", "detail_xcorr", false, false, false, cusum_grid, 1.0, 0.0, 0.5},
      {"detail_xcorr_temp", "detail_xcorr", true, false, false, cusum_grid, 1.0, 0.0, 0.5, true},
      // The flow balance in motion (issue 23): judges every test program, not only at rest.
      {"flow_law", "flow_law", true, true, true, cusum_grid, 1.0, 0.0, 0.5},
      {"flow_law_temp", "flow_law", true, true, true, cusum_grid, 1.0, 0.0, 0.5, true},
  };
}

bool is_condition(std::string_view name) {
  return std::find(std::begin(kConditionNames), std::end(kConditionNames), name) !=
         std::end(kConditionNames);
}

std::size_t design_index(const Candidate& candidate) {
  const auto& thresholds = candidate.raise_thresholds;
  return static_cast<std::size_t>(
      std::find(thresholds.begin(), thresholds.end(), candidate.design_threshold) -
      thresholds.begin());
}

std::string actuator_name(std::size_t candidate, std::size_t threshold) {
  return fmt::format("c{}_t{}", candidate, threshold);
}

}  // namespace leakmon::study
