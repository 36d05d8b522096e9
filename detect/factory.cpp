#include "detect/factory.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "detect/detail_xcorr_detector.hpp"
#include "detect/flow_balance_detector.hpp"
#include "detect/fused_detector.hpp"
#include "detect/index_cusum_detector.hpp"
#include "detect/paper_baseline_detector.hpp"
#include "sim/oil.hpp"

namespace leakmon::detect {

namespace {

constexpr double kMaxSeconds = 86400.0;

bool has_pressure(const AvailableSignals& s) { return s.p1 || s.p2; }
bool has_all(const AvailableSignals& s) { return s.p1 && s.p2 && s.u && s.x; }

// Reads an optional double option into `value`, range-checked at the option's location.
void read(const config::ConfigNode* options, std::string_view key, double& value, double lo,
          double hi) {
  if (options != nullptr) value = options->get_double(key, value, lo, hi);
}

// The rig table holds bore and rod (A = pi/4 (D^2 - d^2)); a configured piston_area keeps the
// rod and sets the bore that gives that area.
void set_piston_area(sim::Parameters& rig, double area) {
  rig.D = std::sqrt(4.0 * area / std::numbers::pi + rig.d * rig.d);
}

void read_learning(const config::ConfigNode* options, LearningSchedule& learning) {
  read(options, "settle_seconds", learning.settle_seconds, 0.0, kMaxSeconds);
  read(options, "learn_seconds", learning.learn_seconds, 1.0, kMaxSeconds);
}

using KeyList = std::span<const std::string_view>;
constexpr std::string_view kLearningKeysData[] = {"settle_seconds", "learn_seconds"};
constexpr std::string_view kIndexKeysData[] = {
    "design_drop",          "false_alarms_per_hour",   "block_seconds",
    "supply_pressure",      "tank_pressure",           "min_drop",
    "temperature_prior",    "temperature_prior_sigma", "drift_guard_seconds",
    "drift_window_seconds", "supply_settle_seconds",   "oil_grade",
    "oil_viscosity_40",     "oil_viscosity_100"};
constexpr std::string_view kFlowKeysData[] = {"supply_pressure",
                                              "tank_pressure",
                                              "command_full_scale",
                                              "valve_coefficient",
                                              "valve_coefficient_uncertainty",
                                              "piston_area",
                                              "rest_speed",
                                              "design_leak",
                                              "false_alarms_per_hour",
                                              "block_seconds",
                                              "sizing_seconds",
                                              "min_leak",
                                              "drift_guard_seconds",
                                              "drift_window_seconds",
                                              "estimate_supply",
                                              "oil_grade",
                                              "oil_viscosity_40",
                                              "oil_viscosity_100"};
constexpr std::string_view kPaperKeysData[] = {"baseline_quantile", "window_seconds",
                                               "raise_fraction", "clear_fraction", "channel"};
constexpr std::string_view kXcorrKeysData[] = {
    "design_shift",         "min_shift",     "false_alarms_per_hour", "block_seconds",
    "supply_pressure",      "tank_pressure", "drift_guard_seconds",   "drift_window_seconds",
    "supply_settle_seconds"};
constexpr KeyList kXcorrKeys = kXcorrKeysData;
constexpr double kXcorrBlockSeconds = 1.6;
constexpr KeyList kLearningKeys = kLearningKeysData, kIndexKeys = kIndexKeysData,
                  kFlowKeys = kFlowKeysData, kPaperKeys = kPaperKeysData;

// Rejects keys outside the union of the given groups, at the key's file:line:column.
void expect_keys(const config::ConfigNode* options, std::initializer_list<KeyList> groups) {
  if (options == nullptr) return;
  std::vector<std::string> allowed;
  for (const auto& group : groups) {
    for (const auto key : group) {
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        allowed.emplace_back(key);
      }
    }
  }
  options->expect_keys(allowed);
}

// The oil grade (MODEL.md "Drifting operating conditions"): `oil_grade` 32, 46 or 68, or the
// two data-sheet viscosities `oil_viscosity_40` and `oil_viscosity_100` [mm^2/s]; the rig's oil
// (VG 46 unless its description says otherwise) when neither is given.
sim::Oil oil_of(const config::ConfigNode& options, const sim::Oil& rig_oil) {
  const auto grade = options.find("oil_grade");
  const auto nu40 = options.find("oil_viscosity_40");
  const auto nu100 = options.find("oil_viscosity_100");
  if (grade && (nu40 || nu100)) grade->fail("give either oil_grade or the two viscosities");
  if (grade) {
    const auto oil = sim::Oil::iso_vg(static_cast<int>(grade->as_int()));
    if (!oil) grade->fail("oil_grade must be 32, 46 or 68 (or give oil_viscosity_40/100)");
    return *oil;
  }
  if (nu40 || nu100) {
    if (!nu40 || !nu100) {
      (nu40 ? *nu40 : *nu100).fail("give both oil_viscosity_40 and oil_viscosity_100");
    }
    const double a = nu40->check_range(nu40->as_double(), 1.0, 10000.0);
    const double b = nu100->check_range(nu100->as_double(), 0.5, 1000.0);
    if (!(a > b)) nu100->fail("oil_viscosity_100 must be below oil_viscosity_40");
    return sim::Oil(a, b);
  }
  return rig_oil;
}

IndexCusumOptions index_options(const config::ConfigNode* options, const AvailableSignals& s,
                                double false_alarm_share, const sim::RigDescription& rig) {
  IndexCusumOptions o;
  o.rig = rig.params;
  o.oil = rig.oil;
  read_learning(options, o.learning);
  read(options, "design_drop", o.design_drop, 0.005, 0.9);
  read(options, "false_alarms_per_hour", o.false_alarms_per_hour, 1e-6, 100.0);
  read(options, "block_seconds", o.block_seconds, 0.01, 60.0);
  read(options, "supply_pressure", o.rig.ps, 1e5, 1e9);
  read(options, "tank_pressure", o.rig.pt, 0.0, 1e8);
  read(options, "min_drop", o.min_drop, 0.0, 0.5);
  read(options, "temperature_prior", o.temperature_prior, -2.0, 2.0);
  read(options, "temperature_prior_sigma", o.temperature_prior_sigma, 1e-4, 10.0);
  read(options, "drift_guard_seconds", o.drift_guard_seconds, 0.0, 3600.0);
  read(options, "drift_window_seconds", o.drift_window_seconds, 0.0, 3600.0);
  read(options, "supply_settle_seconds", o.supply_settle_seconds, 0.0, 3600.0);
  if (options != nullptr) {
    o.oil = oil_of(*options, o.oil);
    if (o.min_drop >= o.design_drop) {
      const auto at = options->find("min_drop");
      (at ? *at : options->at("design_drop")).fail("min_drop must be below design_drop");
    }
  }
  o.false_alarms_per_hour *= false_alarm_share;
  o.use_p1 = s.p1;
  o.use_p2 = s.p2;
  return o;
}

FlowBalanceOptions flow_options(const config::ConfigNode* options, double false_alarm_share,
                                const sim::RigDescription& rig) {
  FlowBalanceOptions o;
  o.rig = rig.params;
  o.oil = rig.oil;
  read_learning(options, o.learning);
  read(options, "supply_pressure", o.rig.ps, 1e5, 1e9);
  read(options, "tank_pressure", o.rig.pt, 0.0, 1e8);
  read(options, "command_full_scale", o.rig.u_max, 1e-3, 1e3);
  read(options, "valve_coefficient", o.rig.Kv, 1e-12, 1.0);
  // A leak of interest is a share of the valve's flow (the test works in command units, MODEL.md
  // "Other rigs"): the defaults are the paper's valve's, scaled to this one; a configured value
  // is taken as it is.
  const double valve_share = o.rig.Kv / sim::Parameters::nominal().Kv;
  o.design_leak *= valve_share;
  o.min_leak *= valve_share;
  read(options, "valve_coefficient_uncertainty", o.valve_coefficient_uncertainty, 0.0, 1.0);
  double piston_area = o.rig.A();
  read(options, "piston_area", piston_area, 1e-8, 10.0);
  set_piston_area(o.rig, piston_area);
  read(options, "rest_speed", o.rest_speed, 1e-6, 10.0);
  read(options, "design_leak", o.design_leak, 1e-16, 1e-8);
  read(options, "false_alarms_per_hour", o.false_alarms_per_hour, 1e-6, 100.0);
  read(options, "block_seconds", o.block_seconds, 0.01, 60.0);
  read(options, "sizing_seconds", o.sizing_seconds, 1.0, kMaxSeconds);
  read(options, "min_leak", o.min_leak, 0.0, 1e-8);
  read(options, "drift_guard_seconds", o.drift_guard_seconds, 0.0, 3600.0);
  read(options, "drift_window_seconds", o.drift_window_seconds, 1.0, 3600.0);
  if (options != nullptr) {
    o.estimate_supply = options->get_bool("estimate_supply", o.estimate_supply);
    o.oil = oil_of(*options, o.oil);
  }
  o.false_alarms_per_hour *= false_alarm_share;
  return o;
}

PaperBaselineOptions paper_options(const config::ConfigNode* options, const AvailableSignals& s) {
  PaperBaselineOptions o;
  read_learning(options, o.learning);
  read(options, "baseline_quantile", o.baseline_quantile, 0.0, 1.0);
  read(options, "window_seconds", o.window_seconds, 0.01, kMaxSeconds);
  read(options, "raise_fraction", o.raise_fraction, 0.0, 1.0);
  read(options, "clear_fraction", o.clear_fraction, 0.0, 1.0);
  o.use_p2 = !s.p1;
  if (options != nullptr) {
    o.use_p2 = options->get_choice("channel", {"p1", "p2"}, s.p1 ? "p1" : "p2") == "p2";
    if (o.clear_fraction >= o.raise_fraction) {
      options->at("clear_fraction").fail("clear_fraction must be below raise_fraction");
    }
  }
  return o;
}

// design_shift / min_shift are in the feature's units: correlation with both chambers, ln of
// the band ratio with one (detail_xcorr_detector.hpp).
DetailXcorrOptions xcorr_options(const config::ConfigNode* options, const AvailableSignals& s,
                                 const sim::RigDescription& rig) {
  DetailXcorrOptions o;
  o.test = index_options(options, s, 1.0, rig);
  // Two windows per block: the sliding feature's neighbouring blocks then share little data.
  o.test.block_seconds = kXcorrBlockSeconds;
  read(options, "block_seconds", o.test.block_seconds, 0.01, 60.0);
  const bool correlation = s.p1 && s.p2;
  double& design = correlation ? o.design_shift_correlation : o.design_shift_ratio;
  double& floor = correlation ? o.min_shift_correlation : o.min_shift_ratio;
  read(options, "design_shift", design, 1e-5, 2.0);
  read(options, "min_shift", floor, 0.0, 2.0);
  if (options != nullptr && floor >= design) {
    const auto at = options->find("min_shift");
    (at ? *at : options->at("design_shift")).fail("min_shift must be below design_shift");
  }
  return o;
}

void require(bool ok, const std::string& kind, const char* what) {
  if (!ok) throw std::invalid_argument("detector '" + kind + "' needs " + what);
}

}  // namespace

std::vector<std::string> detector_kinds() {
  return {"default", "paper", "index_cusum", "flow_balance", "fused", "detail_xcorr"};
}

// Chosen by `leakmon evaluate` (docs/detection.md): with u and x the flow balance alone detects
// every simulated leak down to 1e-13 m^3/(s Pa) within seconds and raised no false alarm in
// 67 healthy hours; fusing the index in only added the index's false alarms. With both chamber
// pressures only, the level-2 detail correlation found 10/20 leaks of 1e-12 within 60 s against
// the index's 4/20, with no false alarm in 32 stationary and 27.6 drifting healthy hours (the
// index: 1 and 1). With one chamber its band ratio is worse than the index, which stays.
std::string default_detector_kind(const AvailableSignals& signals) {
  if (has_all(signals)) return "flow_balance";
  return signals.p1 && signals.p2 ? "detail_xcorr" : "index_cusum";
}

std::unique_ptr<Detector> make_detector(const std::string& kind, const AvailableSignals& signals,
                                        double hop_seconds, const config::ConfigNode* options,
                                        const sim::RigDescription* rig) {
  if (!(hop_seconds > 0.0)) throw std::invalid_argument("detector hop must be positive");
  const sim::RigDescription base = rig != nullptr ? *rig : sim::RigDescription::paper();
  const std::string resolved = kind == "default" ? default_detector_kind(signals) : kind;
  if (resolved == "paper") {
    require(has_pressure(signals), kind, "a chamber pressure (p1 or p2)");
    expect_keys(options, {kLearningKeys, kPaperKeys});
    return std::make_unique<PaperBaselineDetector>(paper_options(options, signals), hop_seconds);
  }
  if (resolved == "index_cusum") {
    require(has_pressure(signals), kind, "a chamber pressure (p1 or p2)");
    expect_keys(options, {kLearningKeys, kIndexKeys});
    return std::make_unique<IndexCusumDetector>(index_options(options, signals, 1.0, base),
                                                hop_seconds);
  }
  if (resolved == "detail_xcorr") {
    require(has_pressure(signals), kind, "a chamber pressure (p1 or p2)");
    expect_keys(options, {kLearningKeys, kXcorrKeys});
    return std::make_unique<DetailXcorrDetector>(xcorr_options(options, signals, base),
                                                 hop_seconds);
  }
  if (resolved == "flow_balance") {
    require(has_all(signals), kind, "p1, p2, u and x");
    expect_keys(options, {kLearningKeys, kFlowKeys});
    return std::make_unique<FlowBalanceDetector>(flow_options(options, 1.0, base), hop_seconds);
  }
  if (resolved == "fused") {
    require(has_all(signals), kind, "p1, p2, u and x");
    expect_keys(options, {kLearningKeys, kIndexKeys, kFlowKeys});
    std::vector<std::unique_ptr<Detector>> members;
    // Flow balance first: it is the one that sizes the leak.
    members.push_back(
        std::make_unique<FlowBalanceDetector>(flow_options(options, 0.5, base), hop_seconds));
    members.push_back(std::make_unique<IndexCusumDetector>(
        index_options(options, signals, 0.5, base), hop_seconds));
    return std::make_unique<FusedDetector>(std::move(members));
  }
  std::string known;
  for (const auto& k : detector_kinds()) known += (known.empty() ? "" : ", ") + k;
  throw std::invalid_argument("unknown detector kind '" + kind + "' (known: " + known + ")");
}

}  // namespace leakmon::detect
