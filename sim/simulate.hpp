// Batch simulation: a whole scenario as a capture (capture/capture.hpp) with the columns
// t,xref,u,x,p1,p2,q_int and metadata naming the origin, seed, controller, effects and every
// parameter that differs from nominal.
#pragma once

#include "capture/capture.hpp"
#include "sim/scenario.hpp"

namespace leakmon::sim {

capture::Capture simulate(const Scenario& scenario);
capture::Metadata capture_metadata(const Scenario& scenario);
// Streams the run to `path` without holding it in memory.
void simulate_to_file(const Scenario& scenario, const std::string& path);

}  // namespace leakmon::sim
