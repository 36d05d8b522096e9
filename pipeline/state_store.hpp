// What the daemon has learned, kept across restarts (systemctl restart, reboot, a crash and
// Restart=on-failure) in its state directory (`state.directory`, systemd's StateDirectory=):
// one file per actuator, so that changing one actuator discards only its own state. A file
// holds a format version, the fingerprint of the configuration the state depends on (the
// actuator's channels incl. ps and temp, detector kind and options, its `rig:`, feature
// settings, sample period), the annunciated alarm state, and the detector's state (detect/detector_state.hpp),
// closed by a checksum. Files are replaced atomically (temporary file in the same directory,
// fsync, rename, fsync of the directory): a crash mid-write leaves the previous file whole.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline/alarm.hpp"
#include "pipeline/config.hpp"
#include "detect/detector_state.hpp"

namespace leakmon::pipeline {

// 2: the learning period's index over the noise floor (healthy_index_ratio), optional; version 1
// files (without it) still load.
inline constexpr int kStateFormatVersion = 2;

// The configuration one actuator's state depends on, as named parts (for messages that say
// what changed) and their hash. Driver names are left out: a state learned by replaying a
// capture (`leakmon learn`, `leakmon replay --state-dir`) fits the daemon reading the same
// channels from its rig.
struct StateFingerprint {
  std::vector<std::pair<std::string, std::string>> parts;
  std::string hash;  // 16 hex digits (FNV-1a 64 of the parts)
  bool operator==(const StateFingerprint& other) const { return hash == other.hash; }
};

// `period_ns`: the sample period of the actuator's group.
StateFingerprint state_fingerprint(const ActuatorConfig& actuator, std::int64_t period_ns);
// The same for every actuator of a configuration (its own group's period), in order.
std::vector<std::pair<std::string, StateFingerprint>> state_fingerprints(
    const DaemonConfig& config);

struct ActuatorState {
  std::string actuator;
  StateFingerprint fingerprint;
  double saved_unix = 0.0;  // wall-clock time of saving [s since 1970]
  AlarmState alarm = AlarmState::normal;
  bool alarm_condition = false;
  // What the learning period's index said about the hydraulic mode (pipeline/mode_visibility.hpp):
  // its median over the noise floor, NaN when not judged.
  double healthy_index_ratio = std::numeric_limits<double>::quiet_NaN();
  detect::DetectorState detector;
};

std::string encode_state(const ActuatorState& state);
// Throws detect::StateError naming what is wrong (truncated, checksum, newer format version).
ActuatorState decode_state(const std::string& text);

class StateStore {
 public:
  explicit StateStore(std::filesystem::path directory);
  const std::filesystem::path& directory() const { return directory_; }
  std::filesystem::path file_of(const std::string& actuator) const;
  // The live page's trend of the actuator (OperatorView::save_history): beside its state, but
  // not part of it (`leakmon state reset` forgets what was learned, not what was seen).
  std::filesystem::path trend_file_of(const std::string& actuator) const;

  // Replaces `target` (a file in the directory) by `text` atomically: temporary file, fsync,
  // rename, fsync of the directory, which is created when missing. Throws std::runtime_error
  // naming the file and the system error, leaving the previous file as it was.
  void write_atomically(const std::filesystem::path& target, const std::string& text) const;

  // Atomic replacement of the actuator's file; creates the directory. Throws std::runtime_error
  // (naming the file and the system error) and leaves the previous file as it was.
  void save(const ActuatorState& state) const;

  struct Loaded {
    std::optional<ActuatorState> state;  // present only when the file fits `expected`
    std::string warning;                 // why a file that exists was set aside
  };
  // No file: neither state nor warning (a first start). A file that cannot be read, is
  // corrupt or truncated, has a newer format or another fingerprint: a warning, no state.
  Loaded load(const std::string& actuator, const StateFingerprint& expected) const;

  // Every state file in the directory (by actuator), and any that failed to decode.
  struct Listing {
    std::vector<ActuatorState> states;
    std::vector<std::pair<std::filesystem::path, std::string>> unreadable;
  };
  Listing list() const;
  // Deletes the actuator's file and its leftover temporary files; true when a file was there.
  bool remove(const std::string& actuator) const;

 private:
  std::filesystem::path directory_;
};

}  // namespace leakmon::pipeline
