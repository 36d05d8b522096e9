#include "pipeline/state_store.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "detect/factory.hpp"
#include "dsp/mode.hpp"

namespace leakmon::pipeline {
namespace {

constexpr std::string_view kMagic = "leakmon-state";
constexpr std::string_view kSuffix = ".state";
constexpr std::string_view kTrendSuffix = ".trend.csv";

std::string fnv1a64(std::string_view text) {
  std::uint64_t hash = 1469598103934665603ull;
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return fmt::format("{:016x}", hash);
}

std::string one_line(std::string text) {
  for (auto& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

std::string options_text(const std::optional<config::ConfigNode>& node) {
  if (!node) return "{}";
  YAML::Emitter out;
  out << YAML::Flow << node->yaml();
  return one_line(out.c_str());
}

// The stated keys with their values as read (shortest exact form): a changed value relearns.
std::string rig_text(const sim::RigDescription& rig) {
  std::string out;
  for (const auto& key : rig.stated) {
    const auto value = sim::rig_value(rig, key);
    if (!out.empty()) out += " ";
    out += value ? fmt::format("{}={}", key, *value)
                 : fmt::format("{}={}/{}", key, rig.oil.nu40(), rig.oil.nu100());
  }
  return out;
}

// Actuator names become file names: keep the safe characters, escape the rest as %XX.
std::string file_stem(const std::string& actuator) {
  std::string out;
  for (unsigned char c : actuator) {
    if (std::isalnum(c) || c == '_' || c == '-') {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("%{:02X}", c);
    }
  }
  return out.empty() ? "%" : out;
}

[[noreturn]] void fail_io(const std::filesystem::path& path, const char* what) {
  throw std::runtime_error(fmt::format("{}: {}: {}", path.string(), what, std::strerror(errno)));
}

void write_all(int fd, const std::string& text, const std::filesystem::path& path) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail_io(path, "write failed");
    done += static_cast<std::size_t>(n);
  }
}

std::string rest_after(std::string_view line, std::string_view key) {
  if (line.size() <= key.size() || line.compare(0, key.size(), key) != 0 ||
      line[key.size()] != ' ') {
    throw detect::StateError(fmt::format("expected '{}', found '{}'", key, line));
  }
  return std::string(line.substr(key.size() + 1));
}

}  // namespace

StateFingerprint state_fingerprint(const ActuatorConfig& actuator, std::int64_t period_ns) {
  StateFingerprint fp;
  const detect::AvailableSignals signals = available_signals(actuator.acquired());
  const std::string kind =
      actuator.detector == "default" ? detect::default_detector_kind(signals) : actuator.detector;
  // "p1=... p2=... u=... x=... xref=... ps=... temp=...": what the fingerprint hash of every
  // saved state reads, so the roles' order and names are part of the state format.
  std::string channels;
  for (const capture::Role role : capture::kRoles) {
    if (!channels.empty()) channels += ' ';
    channels += fmt::format("{}={}", capture::to_string(role), actuator.channels[role].channel);
  }
  fp.parts.emplace_back("channels", channels);
  const auto& f = actuator.features;
  fp.parts.emplace_back(
      "features", fmt::format("wavelet={} level={} window={} step={} mode={}", f.wavelet, f.level,
                              f.window, f.step, dsp::mode_name(f.mode)));
  fp.parts.emplace_back("detector", kind);
  fp.parts.emplace_back("detector_options", options_text(actuator.detector_options));
  // The rig sizes what the detector learns (supply, valve, area, oil); a part only when `rig:`
  // states something, so the paper's rig keeps the fingerprint it had before `rig:` existed.
  if (!actuator.rig.nominal()) fp.parts.emplace_back("rig", rig_text(actuator.rig));
  fp.parts.emplace_back("period_ns", std::to_string(period_ns));
  std::string all;
  for (const auto& [name, value] : fp.parts) all += name + "=" + value + "\n";
  fp.hash = fnv1a64(all);
  return fp;
}

std::vector<std::pair<std::string, StateFingerprint>> state_fingerprints(
    const DaemonConfig& config) {
  std::vector<std::pair<std::string, StateFingerprint>> out;
  for (const auto& actuator : config.actuators) {
    const GroupConfig* group = group_of_driver(config, actuator.channels[capture::Role::p1].driver);
    const std::int64_t period = group != nullptr ? group->period_ns : 0;
    out.emplace_back(actuator.name, state_fingerprint(actuator, period));
  }
  return out;
}

std::string encode_state(const ActuatorState& state) {
  std::string out = fmt::format("{} {}\n", kMagic, kStateFormatVersion);
  out += "actuator " + one_line(state.actuator) + "\n";
  out += "fingerprint " + state.fingerprint.hash + "\n";
  for (const auto& [name, value] : state.fingerprint.parts) {
    out += "config." + name + " " + one_line(value) + "\n";
  }
  out += "saved_unix " + detect::format_double(state.saved_unix) + "\n";
  out += fmt::format("alarm {}\n", to_string(state.alarm));
  out += fmt::format("alarm_condition {}\n", state.alarm_condition ? 1 : 0);
  if (std::isfinite(state.healthy_index_ratio)) {
    out += "healthy_index_ratio " + detect::format_double(state.healthy_index_ratio) + "\n";
  }
  out += "detector\n";
  out += state.detector.text();
  out += "checksum " + fnv1a64(out) + "\n";
  return out;
}

ActuatorState decode_state(const std::string& text) {
  using detect::StateError;
  std::vector<std::string_view> lines;
  std::string_view rest = text;
  while (!rest.empty()) {
    const std::size_t end = rest.find('\n');
    if (end == std::string_view::npos) throw StateError("truncated (last line unfinished)");
    lines.push_back(rest.substr(0, end));
    rest.remove_prefix(end + 1);
  }
  if (lines.empty()) throw StateError("empty file");
  // The version first: a newer format may lay out everything else differently.
  const std::string version_text = rest_after(lines.front(), kMagic);
  int version = 0;
  try {
    version = static_cast<int>(detect::parse_double(version_text));
  } catch (const StateError&) {
    throw StateError("not a leakmon state file (bad format version)");
  }
  if (version > kStateFormatVersion) {
    throw StateError(
        fmt::format("written in format version {} by a newer leakmon (this one reads "
                    "version {})",
                    version, kStateFormatVersion));
  }
  if (version < 1) throw StateError(fmt::format("unknown format version {}", version));
  const std::string_view last = lines.back();
  if (last.rfind("checksum ", 0) != 0) throw StateError("truncated (no checksum line)");
  const std::size_t body_size = text.size() - last.size() - 1;
  if (fnv1a64(std::string_view(text).substr(0, body_size)) != last.substr(9)) {
    throw StateError("corrupt (checksum does not match)");
  }

  ActuatorState state;
  std::size_t i = 1;
  auto next = [&]() -> std::string_view {
    if (i + 1 >= lines.size()) throw StateError("truncated");
    return lines[i++];
  };
  state.actuator = rest_after(next(), "actuator");
  state.fingerprint.hash = rest_after(next(), "fingerprint");
  std::string_view line = next();
  while (line.rfind("config.", 0) == 0) {
    const std::size_t space = line.find(' ');
    if (space == std::string_view::npos) throw StateError("configuration part without value");
    state.fingerprint.parts.emplace_back(std::string(line.substr(7, space - 7)),
                                         std::string(line.substr(space + 1)));
    line = next();
  }
  state.saved_unix = detect::parse_double(rest_after(line, "saved_unix"));
  const std::string alarm = rest_after(next(), "alarm");
  bool known = false;
  for (const auto s : {AlarmState::normal, AlarmState::active_unacknowledged,
                       AlarmState::active_acknowledged, AlarmState::returned_unacknowledged}) {
    if (to_string(s) == alarm) {
      state.alarm = s;
      known = true;
    }
  }
  if (!known) throw StateError("unknown alarm state '" + alarm + "'");
  const std::string condition = rest_after(next(), "alarm_condition");
  if (condition != "0" && condition != "1") throw StateError("alarm_condition not 0 or 1");
  state.alarm_condition = condition == "1";
  line = next();
  if (line.rfind("healthy_index_ratio ", 0) == 0) {
    state.healthy_index_ratio = detect::parse_double(rest_after(line, "healthy_index_ratio"));
    line = next();
  }
  if (line != "detector") throw StateError("expected 'detector'");
  std::string detector;
  for (; i + 1 < lines.size(); ++i) {
    detector += lines[i];
    detector += '\n';
  }
  state.detector = detect::DetectorState::parse(detector);
  return state;
}

StateStore::StateStore(std::filesystem::path directory) : directory_(std::move(directory)) {}

std::filesystem::path StateStore::file_of(const std::string& actuator) const {
  return directory_ / (file_stem(actuator) + std::string(kSuffix));
}

std::filesystem::path StateStore::trend_file_of(const std::string& actuator) const {
  return directory_ / (file_stem(actuator) + std::string(kTrendSuffix));
}

void StateStore::save(const ActuatorState& state) const {
  write_atomically(file_of(state.actuator), encode_state(state));
}

void StateStore::write_atomically(const std::filesystem::path& target,
                                  const std::string& text) const {
  std::error_code error;
  std::filesystem::create_directories(directory_, error);
  if (error) {
    throw std::runtime_error(fmt::format("{}: cannot create the state directory: {}",
                                         directory_.string(), error.message()));
  }
  const std::filesystem::path temporary =
      target.string() + fmt::format(".tmp.{}", static_cast<long>(::getpid()));
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) fail_io(temporary, "cannot create");
  try {
    write_all(fd, text, temporary);
    if (::fsync(fd) != 0) fail_io(temporary, "fsync failed");
  } catch (...) {
    ::close(fd);
    ::unlink(temporary.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    ::unlink(temporary.c_str());
    fail_io(temporary, "close failed");
  }
  if (::rename(temporary.c_str(), target.c_str()) != 0) {
    const int saved = errno;
    ::unlink(temporary.c_str());
    errno = saved;
    fail_io(target, "rename failed");
  }
  // The rename itself is durable only once the directory is.
  const int dir = ::open(directory_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) fail_io(directory_, "cannot open the state directory");
  const int synced = ::fsync(dir);
  ::close(dir);
  if (synced != 0) fail_io(directory_, "fsync of the state directory failed");
}

StateStore::Loaded StateStore::load(const std::string& actuator,
                                    const StateFingerprint& expected) const {
  Loaded loaded;
  const std::filesystem::path path = file_of(actuator);
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return loaded;
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  if (!in) {
    loaded.warning = fmt::format("{}: cannot read the saved state", path.string());
    return loaded;
  }
  ActuatorState state;
  try {
    state = decode_state(buffer.str());
  } catch (const detect::StateError& e) {
    loaded.warning = fmt::format("{}: saved state set aside: {}", path.string(), e.what());
    return loaded;
  }
  if (state.actuator != actuator) {
    loaded.warning = fmt::format("{}: saved state is of actuator '{}', not '{}'", path.string(),
                                 state.actuator, actuator);
    return loaded;
  }
  if (!(state.fingerprint == expected)) {
    std::string changes;
    for (const auto& [name, value] : expected.parts) {
      std::string before = "(none)";
      for (const auto& [old_name, old_value] : state.fingerprint.parts) {
        if (old_name == name) before = old_value;
      }
      if (before != value) {
        changes +=
            fmt::format("{}{}: '{}' -> '{}'", changes.empty() ? "" : "; ", name, before, value);
      }
    }
    loaded.warning = fmt::format("{}: the configuration changed since the state was saved ({})",
                                 path.string(), changes.empty() ? "fingerprint differs" : changes);
    return loaded;
  }
  loaded.state = std::move(state);
  return loaded;
}

StateStore::Listing StateStore::list() const {
  Listing listing;
  std::error_code error;
  if (!std::filesystem::is_directory(directory_, error)) return listing;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(directory_, error)) {
    if (entry.path().extension() == kSuffix && entry.is_regular_file(error)) {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  for (const auto& path : files) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    try {
      listing.states.push_back(decode_state(buffer.str()));
    } catch (const detect::StateError& e) {
      listing.unreadable.emplace_back(path, e.what());
    }
  }
  return listing;
}

bool StateStore::remove(const std::string& actuator) const {
  const std::filesystem::path path = file_of(actuator);
  std::error_code error;
  const bool removed = std::filesystem::remove(path, error);
  if (error) {
    throw std::runtime_error(fmt::format("{}: cannot delete: {}", path.string(), error.message()));
  }
  const std::string prefix = path.filename().string() + ".tmp.";
  for (const auto& entry : std::filesystem::directory_iterator(directory_, error)) {
    if (entry.path().filename().string().rfind(prefix, 0) == 0) {
      std::filesystem::remove(entry.path(), error);
    }
  }
  return removed;
}

}  // namespace leakmon::pipeline
