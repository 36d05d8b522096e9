// Detectors on synthetic observation streams with known truth (synthetic_rig.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "detect/factory.hpp"
#include "detect/flow_balance_detector.hpp"
#include "detect/fused_detector.hpp"
#include "tests/detect/synthetic_pressures.hpp"
#include "tests/detect/synthetic_rig.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::detect {
namespace {

constexpr AvailableSignals kAll{true, true, true, true};
constexpr AvailableSignals kPressuresOnly{true, true, false, false};

TEST(DetectorFactory, DefaultDependsOnAcquiredChannels) {
  EXPECT_EQ(default_detector_kind(kAll), "flow_law");
  EXPECT_EQ(default_detector_kind(kPressuresOnly), "detail_xcorr");
  EXPECT_EQ(default_detector_kind(AvailableSignals{true, false, false, false}), "index_cusum");
  EXPECT_EQ(make_detector("default", kAll, 0.04, nullptr)->name(), "flow_law");
  EXPECT_EQ(make_detector("default", kPressuresOnly, 0.04, nullptr)->name(), "detail_xcorr");
  for (const auto& kind : detector_kinds()) {
    EXPECT_NE(make_detector(kind, kAll, 0.04, nullptr), nullptr) << kind;
  }
}

TEST(DetectorFactory, RejectsUnknownKindAndMissingChannels) {
  EXPECT_THROW(make_detector("magic", kAll, 0.04, nullptr), std::invalid_argument);
  EXPECT_THROW(make_detector("flow_balance", kPressuresOnly, 0.04, nullptr), std::invalid_argument);
  EXPECT_THROW(make_detector("paper", AvailableSignals{}, 0.04, nullptr), std::invalid_argument);
  EXPECT_THROW(make_detector("paper", kAll, 0.0, nullptr), std::invalid_argument);
}

TEST(DetectorFactory, OptionErrorsNameFileLineAndKey) {
  const auto typo =
      config::ConfigNode::load_string("learn_seconds: 30\ndesing_drop: 0.1\n", "detector.yaml");
  try {
    make_detector("index_cusum", kAll, 0.04, &typo);
    FAIL() << "unknown key accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("detector.yaml:2:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("desing_drop"), std::string::npos) << e.what();
  }
  const auto range = config::ConfigNode::load_string("design_drop: 1.5\n", "d.yaml");
  try {
    make_detector("index_cusum", kAll, 0.04, &range);
    FAIL() << "out-of-range value accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("d.yaml:1:"), std::string::npos) << e.what();
  }
  const auto good = config::ConfigNode::load_string(
      "learn_seconds: 30\ndesign_leak: 2.0e-12\nrest_speed: 0.003\n", "good.yaml");
  EXPECT_EQ(make_detector("default", kAll, 0.04, &good)->name(), "flow_law");
}

// One table per kind: its keys are what the configuration accepts, in the order the error
// message lists them, and the same as before the registry (issue 26 renamed none).
TEST(DetectorRegistry, EachKindAcceptsItsTableKeys) {
  const std::vector<std::string> learning = {"settle_seconds", "learn_seconds"};
  auto with_learning = [&](std::vector<std::string> keys) {
    keys.insert(keys.begin(), learning.begin(), learning.end());
    return keys;
  };
  const std::vector<std::string> index = with_learning(
      {"design_drop", "false_alarms_per_hour", "block_seconds", "supply_pressure", "tank_pressure",
       "min_drop", "temperature_prior", "temperature_prior_sigma", "no_excitation_share",
       "drift_guard_seconds", "drift_window_seconds", "supply_settle_seconds",
       // issue 23: learning waits for excitation, judged in the learned regime
       "min_excitation_range", "max_excitation_wait_seconds", "regime_tolerance", "oil_grade",
       "oil_viscosity_40", "oil_viscosity_100"});
  const std::vector<std::string> flow =
      with_learning({"supply_pressure", "tank_pressure", "command_full_scale", "valve_coefficient",
                     "valve_coefficient_uncertainty", "piston_area", "rest_speed", "design_leak",
                     "false_alarms_per_hour", "block_seconds", "sizing_seconds", "min_leak",
                     "drift_guard_seconds", "drift_window_seconds", "estimate_supply",
                     // issue 23: learning waits for excitation, judged state
                     "min_rest_loads", "rest_load_tolerance", "max_excitation_wait_seconds",
                     "limit_to_learned", "no_load_pressure", "judged_memory_seconds", "oil_grade",
                     "oil_viscosity_40", "oil_viscosity_100"});
  std::vector<std::string> fused = index;
  for (const auto& key : flow) {
    if (std::find(fused.begin(), fused.end(), key) == fused.end()) fused.push_back(key);
  }
  const std::map<std::string, std::vector<std::string>> expected = {
      {"paper", with_learning({"baseline_quantile", "window_seconds", "raise_fraction",
                               "clear_fraction", "channel"})},
      {"index_cusum", index},
      {"flow_balance", flow},
      {"fused", fused},
      {"detail_xcorr",
       with_learning({"design_shift", "min_shift", "false_alarms_per_hour", "block_seconds",
                      "supply_pressure", "tank_pressure", "drift_guard_seconds",
                      "drift_window_seconds", "supply_settle_seconds", "min_excitation_range",
                      "max_excitation_wait_seconds", "regime_tolerance"})},
      {"flow_law",
       with_learning({"supply_pressure", "tank_pressure", "command_full_scale", "valve_coefficient",
                      "piston_area", "spool_time_constant", "learn_spool_time_constant",
                      "min_lag_share", "learn_null_offset", "learn_tank_pressure",
                      "learn_before_change", "min_load_spread",
                      // issue 23: learning waits for rest loads or identifying motion
                      "min_rest_loads", "rest_load_tolerance", "min_motion_load_share", "min_load",
                      "design_leak", "false_alarms_per_hour", "block_seconds", "sizing_seconds",
                      "min_leak", "max_leverage_ratio", "range_extension_seconds", "rest_speed",
                      "supply_rest_seconds", "supply_motion_seconds", "judged_memory_seconds",
                      "drift_guard_seconds", "drift_window_seconds", "estimate_supply", "oil_grade",
                      "oil_viscosity_40", "oil_viscosity_100"})}};
  std::vector<std::string> kinds = {"default"};
  for (const auto& kind : detector_registry()) {
    kinds.emplace_back(kind.name);
    ASSERT_TRUE(expected.count(std::string(kind.name))) << kind.name;
    EXPECT_EQ(kind.option_keys(), expected.at(std::string(kind.name))) << kind.name;
    // A key outside the table is refused.
    const AvailableSignals signals = kind.runs_on(kPressuresOnly) ? kPressuresOnly : kAll;
    for (const auto& key : kind.option_keys()) {
      const auto unknown = config::ConfigNode::load_string(key + "_x: 1\n", "k.yaml");
      EXPECT_THROW(make_detector(std::string(kind.name), signals, 0.04, &unknown),
                   config::ConfigError)
          << key;
    }
  }
  EXPECT_EQ(detector_kinds(), kinds);
}

// docs/detection.md lists every kind's options as the registry's tables render them.
TEST(DetectorRegistry, TheDocsHoldTheOptionTables) {
  std::ifstream in(test::source_dir() + "/docs/detection.md");
  std::stringstream docs;
  docs << in.rdbuf();
  const std::string reference = detector_options_reference();
  EXPECT_NE(docs.str().find(reference), std::string::npos)
      << "docs/detection.md's detector options are out of date; the tables are:\n"
      << reference;
  for (const auto& kind : detector_registry()) {
    for (const auto& key : kind.option_keys()) {
      EXPECT_NE(reference.find("`" + key + "`"), std::string::npos) << key;
    }
  }
  // Defaults as the options structs hold them.
  EXPECT_NE(reference.find("| `design_drop` | 0.08 | 0.005 to 0.9 |"), std::string::npos);
  EXPECT_NE(reference.find("| `block_seconds` | 1.6 |"), std::string::npos) << "detail_xcorr";
}

TEST(PaperBaselineDetector, LearnsBaselineAndFlagsALargeDrop) {
  auto detector = make_detector("paper", kPressuresOnly, 0.04, nullptr);
  test::SyntheticRig rig;
  rig.onset = 300.0;
  rig.index_drop = 0.5;  // the paper's rule only reacts to a drop well beyond the scatter
  const test::DetectorRun r = test::run_detector(*detector, rig, 400.0);
  EXPECT_FALSE(r.last.learning);
  EXPECT_GT(r.last.baseline, 15e3);
  EXPECT_LT(r.last.baseline, 40e3);
  EXPECT_LT(r.max_healthy_score, detector->raise_threshold());
  EXPECT_GT(r.first_raise, 300.0);
  EXPECT_LT(r.first_raise, 330.0);
}

TEST(IndexCusumDetector, QuietWhenHealthyAndRaisesAfterADrop) {
  auto detector = make_detector("index_cusum", kPressuresOnly, 0.04, nullptr);
  test::SyntheticRig rig;
  rig.onset = 1800.0;
  rig.index_drop = 0.20;
  const test::DetectorRun r = test::run_detector(*detector, rig, 2000.0);
  EXPECT_LT(r.max_healthy_score, detector->raise_threshold());
  EXPECT_GT(r.first_raise, rig.onset);
  EXPECT_LT(r.first_raise, rig.onset + 90.0);
  EXPECT_TRUE(std::isnan(r.last.leak_coefficient));  // the index cannot size a leak
}

TEST(IndexCusumDetector, NeedsAllConfiguredChambersAndHoldsOnGaps) {
  auto detector = make_detector("index_cusum", kPressuresOnly, 0.04, nullptr);
  test::SyntheticRig rig;
  test::run_detector(*detector, rig, 100.0);
  Observation gap = rig.next();
  gap.index_p2 = kMissing;
  const Decision d = detector->update(gap);
  EXPECT_FALSE(d.learning);
  EXPECT_TRUE(std::isnan(d.index));
}

TEST(FlowBalanceDetector, EstimatesTheLeakWithinItsInterval) {
  auto detector = make_detector("flow_balance", kAll, 0.04, nullptr);
  test::SyntheticRig rig;
  rig.onset = 120.0;
  rig.leak = 1e-12;
  const test::DetectorRun r = test::run_detector(*detector, rig, 300.0);
  EXPECT_LT(r.max_healthy_score, detector->raise_threshold());
  EXPECT_GT(r.first_raise, rig.onset);
  EXPECT_LT(r.first_raise, rig.onset + 30.0);
  ASSERT_FALSE(std::isnan(r.last.leak_coefficient));
  EXPECT_NEAR(r.last.leak_coefficient, 1e-12, r.last.leak_coefficient_ci);
  EXPECT_LT(r.last.leak_coefficient_ci, 0.5e-12);
}

TEST(FlowBalanceDetector, QuietOnAHealthyRigWithStrongNullLeak) {
  auto detector = make_detector("flow_balance", kAll, 0.04, nullptr);
  test::SyntheticRig rig;
  rig.null_leak = 1.5e-12;  // the valve's own leakage is learned, not alarmed on
  rig.kv *= 0.9;
  const test::DetectorRun r = test::run_detector(*detector, rig, 1200.0);
  EXPECT_LT(r.max_healthy_score, detector->raise_threshold());
  EXPECT_NEAR(r.last.leak_coefficient, 0.0, r.last.leak_coefficient_ci + 0.1e-12);
}

// Issue 23: a rig held at one position gives the flow balance one load, from which the healthy
// command's fit against the load extrapolates wildly. Learning waits until blocks at rest cover
// min_rest_loads distinct loads, says so meanwhile, and then judges without a false alarm.
// `hold_at` sets the synthetic rig to rest at x for `seconds` from now.
void hold_at(test::SyntheticRig& rig, double x, double seconds) {
  rig.target = x;
  rig.x = x;
  rig.hold_left = seconds;
}

TEST(FlowBalanceExcitation, AHoldIsNotLearnedFromAndTheWaitIsSaid) {
  auto detector = make_detector("flow_balance", kAll, 0.04, nullptr);
  test::SyntheticRig rig;
  hold_at(rig, 0.02, 300.0);
  std::size_t waiting = 0, held = 0;
  while (rig.t < 300.0) {
    const Decision d = detector->update(rig.next());
    ++held;
    EXPECT_TRUE(d.learning) << rig.t;
    EXPECT_FALSE(d.judged) << rig.t;
    if (d.not_judged_reason == NotJudgedReason::waiting_for_excitation) ++waiting;
  }
  // From the end of the first learning period (92 s) on: waiting, not learning.
  EXPECT_GT(static_cast<double>(waiting), 0.6 * static_cast<double>(held));
  double learned_at = -1.0, judged_at = -1.0;
  double max_score = 0.0;
  while (rig.t < 900.0) {
    const Decision d = detector->update(rig.next());
    if (!d.learning && learned_at < 0) learned_at = rig.t;
    if (d.judged && judged_at < 0) judged_at = rig.t;
    if (!std::isnan(d.score)) max_score = std::max(max_score, d.score);
  }
  ASSERT_GT(learned_at, 300.0);
  EXPECT_LT(learned_at, 300.0 + 2 * 92.0);  // the first period that holds the steps' loads
  EXPECT_GT(judged_at, learned_at);
  EXPECT_LT(judged_at, learned_at + 10.0);
  EXPECT_LT(max_score, detector->raise_threshold());
}

TEST(FlowBalanceExcitation, WaitingTooLongSaysItCannotLearnRatherThanLearningTheHold) {
  FlowBalanceOptions options;
  options.max_excitation_wait_seconds = 180.0;
  FlowBalanceDetector detector(options, 0.04);
  test::SyntheticRig rig;
  hold_at(rig, 0.02, 1e9);
  Decision d;
  while (rig.t < 400.0) d = detector.update(rig.next());
  EXPECT_FALSE(d.learning);
  EXPECT_FALSE(d.judged);
  EXPECT_EQ(d.not_judged_reason, NotJudgedReason::cannot_learn);
  EXPECT_TRUE(std::isnan(d.score));
  EXPECT_EQ(to_string(d.not_judged_reason), "cannot_learn");
}

// After learning on the steps: a hold beyond every learned load is not judged, and neither is
// one near the spring's rest (|p1 - p2| = 0.38 MPa: no leak flow), while the steps are.
TEST(FlowBalanceExcitation, HoldsOutsideTheLearnedLoadsOrWithoutLoadAreNotJudged) {
  auto detector = make_detector("flow_balance", kAll, 0.04, nullptr);
  test::SyntheticRig rig;
  Decision d;
  while (rig.t < 200.0) d = detector->update(rig.next());
  ASSERT_FALSE(d.learning);
  EXPECT_TRUE(d.judged);
  EXPECT_EQ(d.not_judged_reason, NotJudgedReason::none);
  hold_at(rig, 0.09, 60.0);  // 11.4 MPa; the steps reach 6.3 MPa
  while (rig.t < 259.0) d = detector->update(rig.next());
  EXPECT_FALSE(d.judged);
  EXPECT_EQ(d.not_judged_reason, NotJudgedReason::outside_learned_loads);
  hold_at(rig, 0.003, 60.0);
  while (rig.t < 319.0) d = detector->update(rig.next());
  EXPECT_FALSE(d.judged);
  EXPECT_EQ(d.not_judged_reason, NotJudgedReason::no_load);
  while (rig.t < 360.0) d = detector->update(rig.next());
  EXPECT_TRUE(d.judged);
}

// Without the limit the far hold is judged: what limit_to_learned changes (so the test above
// can fail).
TEST(FlowBalanceExcitation, WithoutTheLimitAFarHoldIsJudged) {
  FlowBalanceOptions options;
  options.limit_to_learned = false;
  FlowBalanceDetector detector(options, 0.04);
  test::SyntheticRig rig;
  Decision d;
  while (rig.t < 200.0) d = detector.update(rig.next());
  hold_at(rig, 0.09, 60.0);
  while (rig.t < 259.0) d = detector.update(rig.next());
  EXPECT_TRUE(d.judged);
}

// The healthy command's offset, slope and curvature are fitted on each side of zero load. Steps
// on the positive side and a single 10 s hold on the negative one while learning: the negative
// side's terms rest on one load (a fit judged it by noise), so it is left out of the fit and not
// judged, while the positive side is learned and judged.
TEST(FlowBalanceExcitation, ASideRestedAtOneLoadIsNeitherLearnedNorJudged) {
  auto detector = make_detector("flow_balance", kAll, 0.04, nullptr);
  test::SyntheticRig rig;
  std::mt19937_64 rng{7};
  std::uniform_real_distribution<double> position(0.025, 0.05), hold_seconds(0.5, 4.0);
  bool held_negative = false;
  const auto step_positive_only = [&](double negative_hold_at) {
    if (rig.hold_left > rig.hop) return;  // next() would otherwise draw a target on either side
    if (!held_negative && rig.t > negative_hold_at) {
      rig.target = -0.03;
      rig.hold_left = 10.0 + rig.hop;
      held_negative = true;
    } else {
      rig.target = position(rng);
      rig.hold_left = hold_seconds(rng) + rig.hop;
    }
  };
  Decision d;
  while (rig.t < 150.0) {
    step_positive_only(40.0);
    d = detector->update(rig.next());
  }
  ASSERT_TRUE(held_negative);
  ASSERT_FALSE(d.learning);
  EXPECT_TRUE(d.judged);
  hold_at(rig, -0.03, 30.0);  // the load the negative side rested at while learning
  while (rig.t < 179.0) d = detector->update(rig.next());
  EXPECT_FALSE(d.judged);
  EXPECT_EQ(d.not_judged_reason, NotJudgedReason::outside_learned_loads);
  while (rig.t < 220.0) {
    step_positive_only(1e9);
    d = detector->update(rig.next());
  }
  EXPECT_TRUE(d.judged);
  EXPECT_LT(d.score, detector->raise_threshold());
}

// Pressure-only: an index far below its learned level (no hydraulic mode rung) is not judged.
TEST(IndexCusumDetector, AnIndexFarBelowItsLearnedLevelIsNotJudged) {
  auto detector = make_detector("index_cusum", kPressuresOnly, 0.04, nullptr);
  test::SyntheticRig rig;
  Decision d;
  while (rig.t < 200.0) d = detector->update(rig.next());
  ASSERT_FALSE(d.learning);
  EXPECT_TRUE(d.judged);
  detect::Observation quiet = rig.next();
  quiet.index_p1 = quiet.index_p2 = 0.2 * d.baseline;
  d = detector->update(quiet);
  EXPECT_FALSE(d.judged);
  EXPECT_EQ(d.not_judged_reason, NotJudgedReason::no_excitation);
}

// MODEL.md's valve bias and overlap present from the start: the learned healthy relation takes
// up the offset and dead band (both scale with the orifice root factor), and hops with the
// spool inside the dead band are left out rather than read as missing flow. The leak sits at the
// default minimum of interest, so the floor is lowered to half of it.
TEST(FlowBalanceDetector, LearnsValveBiasAndOverlapAndStillFindsASmallLeak) {
  const auto floor = config::ConfigNode::load_string("min_leak: 2.5e-13\n", "floor.yaml");
  for (const double bias : {0.1, -0.3}) {
    auto detector = make_detector("flow_balance", kAll, 0.04, &floor);
    test::SyntheticRig rig;
    rig.command_offset = bias;
    rig.overlap = 0.02;
    rig.crossing_hops = 5;
    rig.onset = 900.0;
    rig.leak = 5e-13;
    const test::DetectorRun r = test::run_detector(*detector, rig, 1000.0);
    EXPECT_LT(r.max_healthy_score, detector->raise_threshold()) << bias;
    EXPECT_GT(r.first_raise, rig.onset) << bias;
    EXPECT_LT(r.first_raise, rig.onset + 30.0) << bias;
    EXPECT_NEAR(r.last.leak_coefficient, 5e-13, 0.2e-12) << bias;
  }
}

TEST(FusedDetector, RaisesOnLeakAndReportsSize) {
  auto detector = make_detector("fused", kAll, 0.04, nullptr);
  test::SyntheticRig rig;
  rig.onset = 150.0;
  rig.leak = 2e-12;
  rig.index_drop = 0.12;
  const test::DetectorRun r = test::run_detector(*detector, rig, 250.0);
  EXPECT_LT(r.max_healthy_score, 1.0);
  EXPECT_GT(r.first_raise, rig.onset);
  EXPECT_LT(r.first_raise, rig.onset + 20.0);
  EXPECT_NEAR(r.last.leak_coefficient, 2e-12, r.last.leak_coefficient_ci);
}

TEST(Detectors, UpdateAllocatesNothingAfterConstruction) {
  for (const auto& kind : detector_kinds()) {
    auto detector = make_detector(kind, kAll, 0.04, nullptr);
    test::SyntheticRig rig;
    rig.onset = 100.0;
    rig.leak = 2e-12;
    rig.index_drop = 0.1;
    std::uint64_t allocations = 0;
    for (int i = 0; i < 5000; ++i) {  // learning, detection and alarm, all in one scope
      const Observation o = rig.next();
      test::AllocationScope scope;
      detector->update(o);
      allocations += scope.count();
    }
    EXPECT_EQ(allocations, 0u) << kind;
  }
}

// Detectors that compute their own features from the hop's pressure samples: the filters, the
// window and the test run on every hop, through learning, detection and the alarm.
TEST(Detectors, UpdateWithPressureSamplesAllocatesNothing) {
  for (const auto& kind : detector_kinds()) {
    for (const auto& signals : {kPressuresOnly, AvailableSignals{true, false, false, false}}) {
      if (kind == "flow_balance" || kind == "fused" || kind == "flow_law") continue;  // u and x
      auto detector = make_detector(kind, signals, 0.04, nullptr);
      test::SyntheticPressures rig;
      rig.onset = 150.0;
      rig.leak_pole_radius = 0.9;
      std::uint64_t allocations = 0;
      bool judged = false;
      for (int i = 0; i < 6000; ++i) {
        Observation o = rig.next();
        if (!signals.p2) o.p2_samples = {};
        test::AllocationScope scope;
        const Decision d = detector->update(o);
        allocations += scope.count();
        judged |= !std::isnan(d.score);
      }
      EXPECT_EQ(allocations, 0u) << kind;
      if (kind == "detail_xcorr") {
        EXPECT_TRUE(judged);
      }
    }
  }
}

TEST(Detectors, ResetStartsLearningAgain) {
  for (const auto& kind : detector_kinds()) {
    // Learns only from per-sample u and x, which the synthetic rig does not make: its own test
    // (flow_law_test.cpp, FlowLaw.ResetStartsLearningAgain) runs it on the simulator.
    if (kind == "flow_law" || (kind == "default" && default_detector_kind(kAll) == "flow_law")) {
      continue;
    }
    auto detector = make_detector(kind, kAll, 0.04, nullptr);
    test::SyntheticRig rig;
    test::run_detector(*detector, rig, 150.0);
    EXPECT_FALSE(detector->update(rig.next()).learning) << kind;
    detector->reset();
    EXPECT_TRUE(detector->update(rig.next()).learning) << kind;
  }
}

}  // namespace
}  // namespace leakmon::detect
