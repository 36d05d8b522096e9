// Detector states in the layouts earlier builds wrote, read into the layout this build writes,
// so that a daemon updated in place resumes from its state files instead of relearning. The
// layouts read (each detector's version before its pieces saved themselves under names,
// issue 26):
//   flow_balance 2 and 3, index_cusum 3, paper 1, detail_xcorr 1 (its test an index_cusum 3),
//   flow_law 1 (before it learned the spool's time constant: loaded with the stated one kept)
//   and 2 (before the supply waited for a settled rest and the CUSUM's run was kept for the
//   change point: read as then until the piston moves, with an empty run) and 3 (before the
//   learning blocks at rest were told from those that move: its blocks load as moving), 4, 5
//   and 6 (before the null offset, the learned range and the supply read in motion: each loads
//   without it);
//   fused 1 is unchanged (its members' states carry their own layouts); and index_cusum 4 and
//   detail_xcorr 2, written before the feature test waited for excitation and judged in the
//   learned regime only (issue 23): converted with neither (they judge as they did until reset);
//   index_cusum 5 and detail_xcorr 3, written before the regime test read the rest and motion
//   runs: converted without the learned runs (the rest share alone tells the regime, as then).
// The conversion renames and splits lists; it computes nothing, so a converted state decides
// exactly as the old build would have.
#pragma once

#include <string>
#include <string_view>

#include "detect/detector.hpp"
#include "detect/detector_state.hpp"

namespace leakmon::detect {

// `state` in layout `version` of detector `kind`: itself when it is, converted when it is a
// layout above. Throws StateError for another kind or a layout this build does not read.
DetectorState upgraded_state(const DetectorState& state, std::string_view kind, int version);

// A detector's import_state(): `restore(state)` with the state in this build's layout
// `version` (converted when older). On any failure the detector is reset() (it learns afresh)
// and a StateError names its kind.
template <class Restore>
void import_detector_state(Detector& detector, const DetectorState& saved, int version,
                           Restore&& restore) {
  detector.reset();
  try {
    restore(upgraded_state(saved, detector.name(), version));
  } catch (const StateError& e) {
    detector.reset();
    throw StateError(std::string(detector.name()) + ": " + e.what());
  } catch (...) {
    detector.reset();
    throw;
  }
}

// Whether a saved state (any kind, any layout read above; a composite's when any member's) has
// learned its rig: a fitted model or a baseline (`leakmon state show`).
bool has_learned(const DetectorState& state);

}  // namespace leakmon::detect
