// A capture through exactly the daemon's pipeline (replay driver -> acquisition loop -> ring
// buffer -> worker -> features -> detector -> alarms), in process. This is what `leakmon replay`
// runs and what the detection evaluation harness calls. Re-entrant: every call builds its own
// pipeline, so several threads may replay at once.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "capture/capture.hpp"
#include "pipeline/actuator_monitor.hpp"
#include "pipeline/config.hpp"
#include "pipeline/state_store.hpp"
#include "io/event.hpp"

namespace leakmon::pipeline {

struct ReplayOptions {
  // false: as fast as possible on a simulated clock (the loop waits for the worker instead of
  // dropping samples). true: paced at the capture's own rate on the real clock, loop and worker
  // on their own threads as in the daemon.
  bool realtime = false;
  // Non-empty: behave as a daemon restart (FORMATS.md `--state-dir`): resume from what this
  // directory holds for a compatible configuration, and save there when the capture ends.
  std::string state_directory;
};

struct ReplayResult {
  std::vector<io::Event> events;          // in order
  std::uint64_t samples_read = 0;         // rows the loop read from the capture
  std::uint64_t samples_processed = 0;    // samples the worker consumed
  std::uint64_t ring_drops = 0;           // 0 unless realtime and the worker fell behind
  std::vector<ActuatorStatus> actuators;  // state at the end
  std::vector<ActuatorState> learned;     // what each actuator's detector learned, at the end
};

// FORMATS.md built-in defaults: one actuator ("actuator") whose channels are the known columns
// present (p1 required; p2, u, x, xref, ps, temp when present), index on p1 with db8 level 2,
// window 400, step 20, symmetric, the default detector; period from the capture's sample rate.
// Throws capture::CaptureError when the capture has no p1.
DaemonConfig default_replay_config(const capture::Capture& capture);

// The capture replaces the configuration's drivers: actuator channels name capture columns
// (their `driver.` part is ignored), and the single sampling group runs at the capture's rate.
// Throws config::ConfigError / capture::CaptureError on channels the capture does not have.
ReplayResult replay_capture(const capture::Capture& capture, const DaemonConfig& config,
                            const ReplayOptions& options = {});
ReplayResult replay_capture(std::shared_ptr<const capture::Capture> capture,
                            const DaemonConfig& config, const ReplayOptions& options = {});

}  // namespace leakmon::pipeline
