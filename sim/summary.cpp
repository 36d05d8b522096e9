#include "sim/summary.hpp"

#include <fmt/format.h>

#include "capture/units.hpp"

namespace leakmon::sim {
namespace {

// Something with a start time: what it is, in a few words, and when it starts.
struct Onset {
  std::string what;
  double start_s;
  std::string consequence;  // what the capture then lacks
};

std::vector<Onset> onsets(const Scenario& s) {
  std::vector<Onset> out;
  if (s.effects.internal_leakage) {
    out.push_back({"internal_leakage", s.effects.internal_leakage->onset_s, "holds no leak"});
  }
  if (s.effects.external_leakage && s.effects.external_leakage->onset_s > 0.0) {
    out.push_back(
        {"external_leakage", s.effects.external_leakage->onset_s, "holds no external leak"});
  }
  for (const auto& fault : s.faults) {
    out.push_back(
        {fmt::format("sensor fault {} on {}", to_string(fault.kind), to_string(fault.channel)),
         fault.start_s, "holds no such fault"});
  }
  for (const auto& change : s.conditions.supply) {
    out.push_back({fmt::format("supply change to {:g} MPa", change.ps / 1e6), change.t_s,
                   "holds no such change"});
  }
  if (s.conditions.temperature && s.conditions.temperature->start_s > 0.0) {
    out.push_back({"oil warm-up", s.conditions.temperature->start_s, "holds no warm-up"});
  }
  return out;
}

}  // namespace

std::string summary_line(const Scenario& s) {
  std::string line =
      fmt::format("{}, seed {}, {} controller: {:g} s at {:g} Hz ({} rows)",
                  s.origin.empty() ? s.name : s.origin, s.seed, to_string(s.controller),
                  s.duration_s, s.sample_rate_hz, s.samples());
  std::vector<std::string> parts;
  if (s.effects.internal_leakage) {
    const auto& leak = *s.effects.internal_leakage;
    std::string text = fmt::format("internal leak {:.3g} l/min/MPa from t = {:g} s",
                                   units::lpm_per_mpa(leak.C_L), leak.onset_s);
    if (leak.ramp_s > 0.0) text += fmt::format(" (ramp {:g} s)", leak.ramp_s);
    parts.push_back(std::move(text));
  }
  for (const auto& effect : s.effects.describe()) {
    if (effect.name == "internal_leakage") continue;
    std::string text = effect.name;
    for (const auto& param : effect.params) {
      if (const double* value = std::get_if<double>(&param.value)) {
        text += fmt::format(" {}={:g}", param.name, *value);
      } else {
        text += fmt::format(" {}={}", param.name, std::get<std::string>(param.value));
      }
    }
    parts.push_back(std::move(text));
  }
  if (s.conditions.temperature) parts.push_back("oil " + s.conditions.temperature->describe());
  for (const auto& change : s.conditions.supply) {
    parts.push_back(fmt::format("supply to {:g} MPa at t = {:g} s", change.ps / 1e6, change.t_s));
  }
  for (const auto& fault : s.faults) parts.push_back("sensor fault " + fault.describe());
  line += parts.empty() ? "; no effects (healthy)" : fmt::format("; {}", fmt::join(parts, "; "));
  return line;
}

std::vector<std::string> starts_after_end(const Scenario& s) {
  std::vector<std::string> out;
  for (const auto& onset : onsets(s)) {
    if (onset.start_s < s.duration_s) continue;
    out.push_back(
        fmt::format("{} starts at t = {:g} s, after the run ends at t = {:g} s: the "
                    "capture {} (a --duration longer than {:g} s would)",
                    onset.what, onset.start_s, s.duration_s, onset.consequence, onset.start_s));
  }
  return out;
}

}  // namespace leakmon::sim
