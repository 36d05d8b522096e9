// The ladder of spool time constants flow_law weighs while learning (flow_law_detector.hpp), on
// its own so that the conversion of old states (legacy_state.cpp) can lay one out without
// depending on the detector.
#pragma once

#include <cstddef>

namespace leakmon::detect {

// Rungs rig.tau x 2^((i - kStatedTau) / 3): 1/8 to 8 times the stated value.
inline constexpr std::size_t kTauCandidates = 19;
inline constexpr std::size_t kStatedTau = 9;

}  // namespace leakmon::detect
