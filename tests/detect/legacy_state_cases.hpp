// Detector states in the layouts of the build before issue 26 (flow_balance 2, index_cusum 3,
// paper 1, detail_xcorr 1, fused 1 holding the first two), with what that build decided after
// loading them: tests/detect/data/legacy_states/, written by legacy_state_fixtures.cpp built
// against that build (commit 7601cd5). legacy_state_test.cpp loads each state into this build's
// detector, feeds it the same observations and compares every decision to the bit.
//
// Each case runs a synthetic rig through a supply step, drift and (most) a leak, and cuts where
// the state holds the pieces that changed layout: the drift reference's ring, the supply
// tracker in its transient, one chamber's hold levels awaiting a new supply, the CUSUM's
// take-back history, a leak in progress. Uses only the detector interface, so both builds
// compile it.
#pragma once

#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "detect/detector_state.hpp"
#include "detect/factory.hpp"
#include "tests/detect/synthetic_pressures.hpp"
#include "tests/detect/synthetic_rig.hpp"

namespace leakmon::test {

// The supply turned down from 17.2 to 14 MPa over 2 s at 50 s.
inline double early_supply_step(double t) {
  if (t < 50.0) return 17.2e6;
  if (t < 52.0) return 17.2e6 - 3.2e6 * (t - 50.0) / 2.0;
  return 14e6;
}
// A fast cooler: +-4 K around 50 degC every 60 s.
inline double fast_cooler(double t) {
  return 50.0 + 4.0 * std::sin(2.0 * 3.141592653589793 * t / 60.0);
}

struct LegacyCase {
  std::string name;
  std::string kind;
  detect::AvailableSignals signals;
  std::string options;  // the detector's options, YAML
  double cut, end;      // the state is taken at `cut`; decisions are compared until `end`
  // The observations: a SyntheticRig, or (detail_xcorr) SyntheticPressures.
  bool pressures = false;
  void (*rig)(SyntheticRig&) = nullptr;
  void (*samples)(SyntheticPressures&) = nullptr;
};
// For test names and messages.
inline void PrintTo(const LegacyCase& c, std::ostream* out) { *out << c.name; }

inline std::vector<LegacyCase> legacy_cases() {
  const detect::AvailableSignals all{true, true, true, true}, both{true, true, false, false},
      p1{true, false, false, false};
  return {
      {"paper", "paper", both, "{settle_seconds: 1, learn_seconds: 12, window_seconds: 4}", 40.0,
       90.0, false,
       [](SyntheticRig& r) {
         r.onset = 60.0;
         r.leak = 2e-12;
         r.index_drop = 0.5;
       }},
      {"index_cusum_supply_temp", "index_cusum", both,
       "{settle_seconds: 1, learn_seconds: 20, drift_guard_seconds: 5, drift_window_seconds: 20, "
       "supply_settle_seconds: 5}",
       55.0, 110.0, false,
       [](SyntheticRig& r) {
         r.supply = early_supply_step;
         r.temperature = fast_cooler;
         r.report_temp = true;
         r.index_friction_exponent = 0.3;
         r.onset = 80.0;
         r.index_drop = 0.3;
       }},
      {"index_cusum_p1_holds", "index_cusum", p1, "{settle_seconds: 1, learn_seconds: 40}", 66.0,
       130.0, false,
       [](SyntheticRig& r) {
         r.supply = [](double t) { return t < 60.0 ? 17.2e6 : 15e6; };
         r.onset = 100.0;
         r.index_drop = 0.3;
       }},
      {"flow_balance_drift", "flow_balance", all,
       "{settle_seconds: 1, learn_seconds: 15, drift_guard_seconds: 5, drift_window_seconds: 15}",
       52.0, 110.0, false,
       [](SyntheticRig& r) {
         r.supply = early_supply_step;
         r.temperature = fast_cooler;
         r.onset = 80.0;
         r.leak = 2e-12;
       }},
      {"flow_balance_ps_temp", "flow_balance", all, "{settle_seconds: 1, learn_seconds: 15}", 51.0,
       90.0, false,
       [](SyntheticRig& r) {
         r.supply = early_supply_step;
         r.report_supply = true;
         r.temperature = fast_cooler;
         r.report_temp = true;
         r.onset = 70.0;
         r.leak = 1e-12;
       }},
      {"fused", "fused", all,
       "{settle_seconds: 1, learn_seconds: 15, drift_guard_seconds: 5, drift_window_seconds: 15, "
       "supply_settle_seconds: 5}",
       85.0, 110.0, false,
       [](SyntheticRig& r) {
         r.supply = early_supply_step;
         r.temperature = fast_cooler;
         r.onset = 80.0;
         r.leak = 2e-12;
         r.index_drop = 0.3;
       }},
      // The shifts that build's defaults were (issue 23 changed them; the state does not hold
      // them).
      {"detail_xcorr", "detail_xcorr", both,
       "{settle_seconds: 1, learn_seconds: 20, design_shift: 0.005, min_shift: 0.00125}", 45.0,
       100.0, true, nullptr,
       [](SyntheticPressures& r) {
         r.supply_after = 14e6;
         r.supply_step_at = 40.0;
         r.onset = 70.0;
         r.leak_pole_radius = 0.9;
       }},
      {"detail_xcorr_p1", "detail_xcorr", p1,
       "{settle_seconds: 1, learn_seconds: 20, min_shift: 0.03}", 75.0, 100.0, true, nullptr,
       [](SyntheticPressures& r) {
         r.onset = 70.0;
         r.leak_pole_radius = 0.85;
       }},
  };
}

// The case's observations, one hop per next().
class LegacyStream {
 public:
  explicit LegacyStream(const LegacyCase& c) : case_(c) {
    if (c.rig != nullptr) c.rig(rig_);
    if (c.samples != nullptr) c.samples(pressures_);
  }
  detect::Observation next() {
    if (!case_.pressures) return rig_.next();
    detect::Observation o = pressures_.next();
    if (!case_.signals.p2) o.p2_samples = {};
    return o;
  }

 private:
  const LegacyCase& case_;
  SyntheticRig rig_;
  SyntheticPressures pressures_;
};

inline std::unique_ptr<detect::Detector> make_legacy_detector(const LegacyCase& c) {
  const auto options = config::ConfigNode::load_string(c.options, c.name);
  return detect::make_detector(c.kind, c.signals, 0.04, &options);
}

// One decision as a line of exact numbers (detector_state.hpp's format_double).
inline std::string decision_line(const detect::Observation& o, const detect::Decision& d) {
  std::string line = detect::format_double(o.t);
  for (const double v : {d.score, d.learning ? 1.0 : 0.0, d.learning_hops_left, d.baseline, d.index,
                         d.leak_coefficient, d.leak_coefficient_ci, d.viscosity_ratio}) {
    line += ' ';
    line += detect::format_double(v);
  }
  return line;
}

// FNV-1a 64 of the lines, as 16 hex digits.
inline std::string lines_hash(const std::vector<std::string>& lines) {
  std::uint64_t hash = 1469598103934665603ull;
  for (const auto& line : lines) {
    for (const unsigned char c : line + "\n") {
      hash ^= c;
      hash *= 1099511628211ull;
    }
  }
  static const char* digits = "0123456789abcdef";
  std::string out(16, '0');
  for (int i = 15; i >= 0; --i, hash >>= 4) out[static_cast<std::size_t>(i)] = digits[hash & 15];
  return out;
}

// Every `kSampleEvery`-th decision line is kept in the fixture, to say where a mismatch begins.
inline constexpr std::size_t kSampleEvery = 25;

}  // namespace leakmon::test
