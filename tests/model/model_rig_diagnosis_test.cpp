// Issue 24 end to end: the model check on other rigs told their description, on descriptions
// with one value stated wrong, and on effects that start inside the capture; the JSON of
// FORMATS.md for each. Most tests draw fresh rigs and cases each run (seeds printed;
// LEAKMON_TEST_SEED reproduces a run), with quorums from the per-draw rates `leakmon model
// evaluate --rigs other` measured (docs/model-check.md, "Other rigs"), not from hope; the
// others run fixed cases of those evaluations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "model/diagnosis.hpp"
#include "model/evaluation.hpp"
#include "model/report.hpp"
#include "model/result_json.hpp"
#include "model/synthetic_case.hpp"
#include "tests/model/test_seed.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::model {
namespace {

CaseSettings other_rig(double seconds, const std::string& misstate = "") {
  CaseSettings s;
  s.duration_s = seconds;
  s.other_rig = true;
  s.misstate = misstate;
  return s;
}

std::string causes(const Diagnosis& d) {
  std::string out;
  for (const auto& c : d.causes) out += (out.empty() ? "" : "+") + c.effect;
  return out.empty() ? d.cause : out;
}

// The cause named for `effect`, or null when it was not named.
const NamedCause* named_cause(const Diagnosis& d, const std::string& effect) {
  const auto it = std::find_if(d.causes.begin(), d.causes.end(),
                               [&](const NamedCause& cause) { return cause.effect == effect; });
  return it == d.causes.end() ? nullptr : &*it;
}

// Whether the steps say that `effect` was accepted in the place of `replaces`.
bool swap_said(const Diagnosis& d, const std::string& effect, const std::string& replaces) {
  return std::any_of(d.steps.begin(), d.steps.end(), [&](const SelectionStep& s) {
    return s.accepted && s.effect == effect && s.replaces == replaces;
  });
}

Diagnosis diagnose_case(const SyntheticCase& c) {
  const MeasuredRecord record = measured_record(simulate_case(c));
  Diagnosis d = diagnose(record, c.told);
  std::printf("  %s\n  told: %s\n  -> %s (NRMSE %.4f -> %.4f, floor %.4f)\n",
              c.scenario.name.c_str(), sim::describe(c.told).c_str(), causes(d).c_str(),
              d.nrmse_before, d.nrmse_after, d.nrmse_floor);
  return d;
}

// `python_check` asserts on the JSON `r` (Python's json module reads it, as other tools do).
void check_json(const Diagnosis& d, const std::string& name, const std::string& python_check) {
  const std::string dir = test::scratch_dir(name);
  std::ofstream(dir + "/result.json") << diagnosis_json(d);
  const std::string command = test::python() +
                              " -c \"import json,sys; r=json.load(open(sys.argv[1])); " +
                              python_check + "\" " + dir + "/result.json";
  EXPECT_EQ(std::system(command.c_str()), 0) << diagnosis_json(d);
}

// A valve bias and a supply droop (a pair case of the evaluation below) whose dead band, named
// first, gave way to the bias: the bias then the droop, the bias within 25 %, and the swap
// said in the steps.
Diagnosis expect_the_bias_swapped_in_for_the_dead_band(std::uint64_t seed) {
  const SyntheticCase c = draw_case(seed, "valve_bias+supply_droop", other_rig(180.0));
  Diagnosis d = diagnose_case(c);
  EXPECT_EQ(causes(d), "valve_bias+supply_droop");
  if (!d.causes.empty() && !d.causes[0].params.empty()) {
    EXPECT_NEAR(d.causes[0].params.front().value, c.main_value, 0.25 * std::abs(c.main_value));
  }
  EXPECT_TRUE(swap_said(d, "valve_bias", "valve_overlap"));
  return d;
}

// Several effects at once: forward selection names the best single effect first. Fixed case
// 817111 of `model evaluate --rigs other --duration 180 --classes pair --seed 817100`: a valve
// bias (u0 -0.14 V) and a supply droop on a 68 mm rig. Alone the dead band led the bias by 0.005
// in score (a bias and a dead band both shape the flow near null), the droop was named next to
// it, and the bias, third, gained too little beside them: `valve_overlap+supply_droop` at 2.1 x
// the true model's held-out error. A near-tie of the first cause is now tried in its place
// beside the others: the bias and the droop, the bias within 25 %, and the swap said in the steps.
TEST(SeveralEffects, ANearTieOfTheFirstCauseTakesItsPlaceWhereItFitsTheOthersBetter) {
  const Diagnosis d = expect_the_bias_swapped_in_for_the_dead_band(817111);
  check_json(d, "model_rig_swap",
             "s=[x for x in r['steps'] if x.get('replaces')]; assert len(s)==1; "
             "assert s[0]['effect']=='valve_bias' and s[0]['replaces']=='valve_overlap'");
}

// The runner-up need not be a hair behind: fixed case 817103 of the same evaluation, a valve
// bias (u0 0.090 V) and a supply droop on a 184 kg, 66 mm rig. Alone the dead band led the bias
// by 0.022 (0.856 against 0.833), outside the 0.02 the swap first allowed, and the dead band
// with the droop was named at 2.6 x the true model's held-out error: the bias and the droop.
TEST(SeveralEffects, ARunnerUpANarrowMarginBehindIsTriedInItsPlace) {
  expect_the_bias_swapped_in_for_the_dead_band(817103);
}

// Nor within a tenth: fresh case 817213 of `model evaluate --rigs other --duration 180 --classes
// pair --seed 817200`, a leak of 1.13e-12 beside a 27 ms spool lag on a 48 kg, 38 mm rig (its
// own spool 10.7 ms). Alone the dead band scored 0.533 and the leak 0.431 (0.81 of it, outside
// the 0.9 the swap then allowed); the dead band and the lag were named. Every refined,
// plausible runner-up is now tried: the leak and the lag, each within 25 %, the swap said.
TEST(SeveralEffects, ARunnerUpFarBehindAloneIsTriedInItsPlace) {
  const SyntheticCase c = draw_case(817213, "spool_lag+internal_leakage", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(d.causes.size(), 2u) << causes(d);
  const NamedCause* lag = named_cause(d, "spool_lag");
  const NamedCause* leak = named_cause(d, "internal_leakage");
  ASSERT_NE(lag, nullptr) << causes(d);
  ASSERT_NE(leak, nullptr) << causes(d);
  EXPECT_NEAR(lag->params.front().value, c.main_value, 0.25 * c.main_value);
  ASSERT_EQ(c.effects.size(), 2u);
  ASSERT_EQ(c.effects[1].effect, "internal_leakage");
  EXPECT_NEAR(leak->params.front().value, c.effects[1].main_value, 0.25 * c.effects[1].main_value);
  EXPECT_TRUE(swap_said(d, "internal_leakage", "valve_overlap"));
}

// A further effect's joint fit starts from the calibration the causes named before it left, and
// that calibration may have soaked up the effect being added. Fixed case 817113 of the same
// evaluation: a 20.7 ms spool lag beside a leak on a 74 kg, 50 mm rig. Fitted from the leak's
// calibration, the lag put a calibrated value on its bound and was refused as trading with the
// calibration; only the leak was named. Restarted from the catalogue calibration it needs no
// bound: both named, the lag within 25 %.
TEST(SeveralEffects, AFurtherEffectThatNeedsABoundIsFittedAgainFromTheCatalogue) {
  const SyntheticCase c = draw_case(817113, "spool_lag+internal_leakage", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(d.causes.size(), 2u) << causes(d);
  const NamedCause* lag = named_cause(d, "spool_lag");
  ASSERT_NE(lag, nullptr) << causes(d);
  EXPECT_NEAR(lag->params.front().value, c.main_value, 0.25 * c.main_value);
  EXPECT_NE(named_cause(d, "internal_leakage"), nullptr) << causes(d);
  EXPECT_TRUE(d.at_bound.empty());
}

// Only the best variant of each effect (which channel, which chamber) gets a full fit, and the
// screening on a few segments can rank the wrong one first by a hair. Fresh case 817201 of
// `model evaluate --rigs other --duration 180 --classes pair --seed 817200`: a 3.8 ms lag of p2
// beside a dead band. p1's lag screened 0.4 % ahead of p2's, its full fit went to the lag's
// lower bound (implausible), and only the dead band was named. The next variant of the same
// effect is now fitted in its place: the lag on p2, within 25 %, beside the dead band.
TEST(SeveralEffects, AVariantThatFitsImplausiblyGivesWayToTheNextOfTheSameEffect) {
  const SyntheticCase c = draw_case(817201, "sensor_lag+valve_overlap", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(d.causes.size(), 2u) << causes(d);
  const NamedCause* lag = named_cause(d, "sensor_lag");
  ASSERT_NE(lag, nullptr) << causes(d);
  const auto tau = std::find_if(lag->params.begin(), lag->params.end(),
                                [](const NamedValue& v) { return !v.is_text(); });
  ASSERT_NE(tau, lag->params.end());
  EXPECT_NEAR(tau->value, c.main_value, 0.25 * c.main_value);
  const auto channel = std::find_if(lag->params.begin(), lag->params.end(),
                                    [](const NamedValue& v) { return v.name == "channel"; });
  ASSERT_NE(channel, lag->params.end());
  EXPECT_EQ(channel->text, "p2");
  EXPECT_NE(named_cause(d, "valve_overlap"), nullptr) << causes(d);
}

// Coulomb friction's fit has a minimum near each force that changes which segments stick. Fresh
// case 817215 of the same evaluation: a 368 N friction beside a valve bias on a 9.3 kg, 35 mm
// rig without a spring. From the library's start, after the bias, the friction stopped at 276 N
// with the viscous friction on its bound and was refused, and a sensor lag was named beside the
// bias (NRMSE 0.62 against the true model's 0.045). Started again at three times the library's
// start from the catalogue calibration: the bias and the friction, each within 25 %.
TEST(SeveralEffects, AFurtherFrictionIsFittedAgainFromAHigherForce) {
  const SyntheticCase c = draw_case(817215, "coulomb_friction+valve_bias", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(causes(d), "valve_bias+coulomb_friction");
  EXPECT_NEAR(d.causes[1].params.front().value, c.main_value, 0.25 * c.main_value);
  ASSERT_EQ(c.effects.size(), 2u);
  ASSERT_EQ(c.effects[1].effect, "valve_bias");
  EXPECT_NEAR(d.causes[0].params.front().value, c.effects[1].main_value,
              0.25 * std::abs(c.effects[1].main_value));
}

// A healthy rig drawn from MODEL.md's "Other rigs", told its description: `none`. Two rigs per
// run; the evaluation's rate of `none` on told healthy rigs (docs/model-check.md) makes a run
// with neither `none` about one in 1000, and a rig_parameter on a told rig was never seen.
TEST(OtherRig, HealthyRigToldItsDescriptionIsNone) {
  const auto seed = test::model_test_seed("OtherRig.HealthyRigToldItsDescriptionIsNone");
  int nones = 0;
  for (std::uint64_t i = 0; i < 2; ++i) {
    const Diagnosis d = diagnose_case(draw_case(seed + i, "none", other_rig(90.0)));
    nones += d.cause == "none";
    EXPECT_TRUE(d.rig_check.findings.empty()) << "seed " << seed + i;
    if (d.cause == "none") {
      check_json(d, "model_rig_healthy",
                 "assert r['cause']=='none'; assert r['causes']==[]; "
                 "assert r['rig']['changed']==[]; assert 'supply_pressure' in r['rig']['stated']");
    }
  }
  EXPECT_GE(nones, 1);
}

// A supply stated 15-30 % off: `rig_parameter` supply_pressure with the stated and the fitted
// value (within 10 % of the truth), named first, and no transducer offset (the shifted levels
// it would otherwise be taken for).
TEST(OtherRig, MisstatedSupplyIsARigParameterNotASensorOffset) {
  const auto seed =
      test::model_test_seed("OtherRig.MisstatedSupplyIsARigParameterNotASensorOffset");
  const SyntheticCase c = draw_case(seed, "none", other_rig(90.0, "supply_pressure"));
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(d.cause, "rig_parameter");
  ASSERT_FALSE(d.causes.empty());
  const auto& params = d.causes.front().params;
  ASSERT_EQ(params.size(), 3u);
  EXPECT_EQ(params[0].text, "supply_pressure");
  EXPECT_EQ(params[1].value, c.misstated_stated);
  EXPECT_NEAR(params[2].value, c.misstated_true, 0.1 * c.misstated_true);
  for (const auto& cause : d.causes) EXPECT_NE(cause.effect, "sensor_offset");
  EXPECT_LT(d.nrmse_after, d.nrmse_before);
  char expected[160];
  std::snprintf(expected, sizeof expected,
                "assert abs(c['params']['fitted']/%.9g-1)<0.1; "
                "assert abs(c['params']['stated']/%.9g-1)<1e-5",
                c.misstated_true, c.misstated_stated);
  check_json(d, "model_rig_supply",
             std::string("c=r['causes'][0]; assert r['cause']=='rig_parameter'; "
                         "assert c['cause']=='rig_parameter'; "
                         "assert c['params']['parameter']=='supply_pressure'; ") +
                 expected +
                 "; assert 'onset_s' not in c; "
                 "assert r['rig']['changed'][0]['parameter']=='supply_pressure'; "
                 "assert abs(r['rig']['assumed']['supply_pressure']-c['params']['fitted'])<1; "
                 "assert set(r['calibrated'])=={'beta','Kv','m','b'}");
}

// A load stiffness stated 40-80 % off: `rig_parameter` load_stiffness, named first and fitted
// within 10 %, on every draw (the evaluations: every mis-stated value found and fitted). Named
// *alone* on about nine draws in ten (docs/model-check.md: 31 of 36, 16 of 18, 11 of 11): the
// misses carry a second, small library effect where the true model itself stays above the
// estimated noise floor (seed 15528031207838567108: coulomb_friction 11 N, the true model
// 0.0222 against a floor of 0.0126). So per run, four draws: alone on at least two (a run fails
// by chance about once in 300 at that rate).
TEST(OtherRig, MisstatedLoadStiffnessIsARigParameter) {
  const auto first =
      test::model_test_seed("OtherRig.MisstatedLoadStiffnessIsARigParameter (first of 4)");
  int alone = 0;
  for (std::uint64_t i = 0; i < 4; ++i) {
    const SyntheticCase c = draw_case(first + i, "none", other_rig(90.0, "load_stiffness"));
    const Diagnosis d = diagnose_case(c);
    ASSERT_EQ(d.cause, "rig_parameter") << "seed " << first + i;
    ASSERT_FALSE(d.causes.empty());
    EXPECT_EQ(d.causes.front().params[0].text, "load_stiffness") << "seed " << first + i;
    EXPECT_NEAR(d.causes.front().params[2].value, c.misstated_true, 0.1 * c.misstated_true)
        << "seed " << first + i;
    alone += d.causes.size() == 1;
  }
  EXPECT_GE(alone, 2) << "load stiffness named alone, of 4";
}

// A soft spring on a strong actuator (CI's draw of 2026-11-29): 27.7 kN/m stated, 17.4 kN/m
// true, on a 61 mm bore at 23 MPa. The balance fitted 17.4 +- 0.02 kN/m, yet the check named
// nothing: the change (10.4 kN/m) sat under the floor meant for rigs stated without a spring
// (1 % of A (ps - pt) / 0.05 m, 10.8 kN/m here). A stated spring is judged by its tolerance.
TEST(OtherRig, ASoftSpringOnAStrongActuatorIsStillARigParameter) {
  const SyntheticCase c =
      draw_case(1777212615571684931ULL, "none", other_rig(90.0, "load_stiffness"));
  ASSERT_LT(c.misstated_true, 0.7 * c.misstated_stated);
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(d.cause, "rig_parameter");
  EXPECT_EQ(d.causes.front().params[0].text, "load_stiffness");
  EXPECT_NEAR(d.causes.front().params[2].value, c.misstated_true, 0.1 * c.misstated_true);
  EXPECT_LT(d.nrmse_after, d.nrmse_before);
}

// The capture: a leak opening inside a capture of the paper's rig at constant
// temperature. Named internal_leakage with its onset within 2 s (on main it was `unexplained`,
// "drift such as the oil warming up"); the JSON carries onset_s.
TEST(Onset, LeakOpeningInsideTheCaptureIsNamedWithItsOnset) {
  const auto seed = test::model_test_seed("Onset.LeakOpeningInsideTheCaptureIsNamedWithItsOnset");
  CaseSettings settings;
  settings.duration_s = 120.0;
  settings.onset = true;
  const SyntheticCase c = draw_case(seed, "internal_leakage", settings);
  const Diagnosis d = diagnose_case(c);
  std::printf("  true onset %.2f s, C_L %.3g\n", c.onset_s, c.main_value);
  ASSERT_EQ(d.cause, "internal_leakage") << causes(d);
  EXPECT_EQ(d.causes.size(), 1u) << causes(d);
  EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0);
  EXPECT_NEAR(d.causes.front().params.front().value, c.main_value, 0.25 * c.main_value);
  char expected[96];
  std::snprintf(expected, sizeof expected, "assert abs(c['onset_s']-%.6f)<2", c.onset_s);
  check_json(d, "model_rig_onset",
             std::string("c=r['causes'][0]; assert c['cause']=='internal_leakage'; "
                         "a,b=c['onset_range_s']; assert a<=c['onset_s']<=b; ") +
                 expected);
}

CaseSettings onset_on_other_rig(double seconds) {
  CaseSettings s = other_rig(seconds);
  s.onset = true;
  return s;
}

// Fixed case 796000 of `model evaluate --rigs other --classes onset` (180 s): a leak opening at
// 117.3 s, found at its onset and named, then turned `unexplained` by the drift test: the named
// model's b, fitted on the last third, sat on its lower bound with the clamp's error of zero
// (58.1 +- 1.4 early, 30.0 +- 0 late, z 20). Named alone with its onset within 2 s, no drift.
TEST(Onset, ValueOnItsBoundDoesNotMakeANamedLeakDrift) {
  const SyntheticCase c = draw_case(796000, "internal_leakage", onset_on_other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  for (const auto& m : d.drift) {
    std::printf("  drift %s: %.4g +- %.3g -> %.4g +- %.3g, z %.1f\n", m.parameter.c_str(), m.early,
                m.early_error, m.late, m.late_error, m.z);
  }
  std::printf("  true onset %.2f s, C_L %.3g\n", c.onset_s, c.main_value);
  ASSERT_EQ(causes(d), "internal_leakage");
  EXPECT_FALSE(d.drifts);
  EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0);
  EXPECT_NEAR(d.causes.front().params.front().value, c.main_value, 0.25 * c.main_value);
}

// Fixed case 796018 of the same run: a supply droop from 85.1 s. A droop shows only while the
// piston moves (the valve's flow); split over all segments, the holds hid its onset, and
// fitted from the start it had no plausible candidate: `unexplained`. Named alone with its
// onset within 2 s.
TEST(Onset, EffectShowingOnlyInMotionIsNamedWithItsOnset) {
  const SyntheticCase c = draw_case(796018, "supply_droop", onset_on_other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  std::printf("  true onset %.2f s, R_s %.3g; change point %.2f s (t %.1f)\n", c.onset_s,
              c.main_value, d.change_point ? d.change_point->t_s : 0.0,
              d.change_point ? d.change_point->statistic : 0.0);
  ASSERT_EQ(causes(d), "supply_droop");
  EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0);
  // The stretch the data allow holds the reported onset and the true one.
  const auto& cause = d.causes.front();
  std::printf("  onset stretch %.2f-%.2f s\n", cause.onset_earliest_s, cause.onset_latest_s);
  EXPECT_LE(cause.onset_earliest_s, cause.onset_s);
  EXPECT_GE(cause.onset_latest_s, cause.onset_s);
  EXPECT_GE(c.onset_s, cause.onset_earliest_s - 2.0);
  EXPECT_LE(c.onset_s, cause.onset_latest_s + 2.0);
}

// Fixed cases 811031 and 811029 of `model evaluate --rigs other --classes misstated,onset
// --seed 811000` (180 s): a supply droop from 109.0 s whose change point lay at 118.5 s, and a
// 42 ms spool lag from 124.6 s split at 129.5 s. Both show only while the piston moves; the
// onset search (+-4 s around the split) found the summed error still falling, or flat, at its
// window's edge, and took 116.55 s and 127.5 s (7.5 s and 2.9 s late). The window now widens
// while the flat stretch reaches its edge: named alone with the onset within 2 s.
TEST(Onset, AnOnsetHoldsBeforeTheChangePointIsFoundByWideningTheSearch) {
  for (const auto& [seed, effect] :
       {std::pair<std::uint64_t, const char*>{811031, "supply_droop"}, {811029, "spool_lag"}}) {
    const SyntheticCase c = draw_case(seed, effect, onset_on_other_rig(180.0));
    const Diagnosis d = diagnose_case(c);
    std::printf("  true onset %.2f s; change point %.2f s (t %.1f)\n", c.onset_s,
                d.change_point ? d.change_point->t_s : 0.0,
                d.change_point ? d.change_point->statistic : 0.0);
    ASSERT_EQ(causes(d), effect) << seed;
    EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0) << seed;
  }
}

// An effect that starts late leaves few segments after it: the split's Welch t stays small
// however large the step, and a large step is taken at a lower t (DiagnosisSettings::
// large_change_step). A fixed case of `model evaluate --rigs other --classes misstated,onset
// --seed 811000`: 811067, a supply droop from 139.6 s of 180, split at t 4.87 with its error
// e^2.9 times as large after it, was `unexplained` (no onset variant tried below t 5).
TEST(Onset, ALateOnsetWithALargeStepIsTriedBelowTheUsualStatistic) {
  const SyntheticCase c = draw_case(811067, "supply_droop", onset_on_other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_TRUE(d.change_point.has_value());
  std::printf("  true onset %.2f s; change point %.2f s (t %.2f, log step %.2f)\n", c.onset_s,
              d.change_point->t_s, d.change_point->statistic, d.change_point->step);
  const DiagnosisSettings settings;
  ASSERT_LT(d.change_point->statistic, settings.min_change_statistic)
      << "the split passes the usual statistic: the case no longer tests the large step";
  ASSERT_EQ(causes(d), "supply_droop");
  EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0);
}

// A named model whose calibration moves between the capture's thirds against the nominal's move
// trades it with its cause's parameters; it is no warm-up left unexplained (model/diagnosis.cpp):
// fixed cases of `model evaluate --rigs other --classes misstated,onset --seed 811000`. 811023,
// a Coulomb friction from 56.9 s on a 73 kg rig: the named b fell 12 % while the nominal b rose
// 60 %; 811007, a dead band from 129.4 s: the named beta rose 23 % while the nominal beta held
// still. Both were turned `unexplained` by the drift test with the cubic start velocity.
TEST(Onset, ANamedModelTradingItsCalibrationWithItsCauseDoesNotDrift) {
  for (const auto& [seed, effect] :
       {std::pair<std::uint64_t, const char*>{811023, "coulomb_friction"},
        {811007, "valve_overlap"}}) {
    const SyntheticCase c = draw_case(seed, effect, onset_on_other_rig(180.0));
    const Diagnosis d = diagnose_case(c);
    for (const auto& comparison : d.drift) {
      std::printf("  %s: %.4g -> %.4g (z %.1f)%s\n", comparison.parameter.c_str(), comparison.early,
                  comparison.late, comparison.z, comparison.drifts ? " drifts" : "");
    }
    ASSERT_EQ(causes(d), effect) << seed;
    EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0) << seed;
  }
}

CaseSettings program_onset_on_other_rig() {
  CaseSettings s = onset_on_other_rig(180.0);
  s.program = true;
  return s;
}

void print_splits(const SyntheticCase& c, const Diagnosis& d) {
  std::printf("  true onset %.2f s; strongest split %.2f s (t %.1f)\n", c.onset_s,
              d.change_point->t_s, d.change_point->statistic);
  for (const auto& split : d.onsets_tried) {
    std::printf("  tried %.2f s (t %.1f)\n", split.t_s, split.statistic);
  }
}

// Under a test program the nominal model's error follows the program, and its strongest split
// can be a phase change instead of the effect. Fixed case 818214 of `model evaluate --programs
// --rigs other --classes onset --seed 818200` (180 s): a 29 ms spool lag from 72.56 s on a 27 mm
// rig whose program holds for its first 55 s and then sweeps. The errors split at the hold's
// end (t 22); the candidates' gains split at 72.5 s (t 18) but only the strongest split was
// tried: `unexplained`, the lag read as drift. Both are tried now; named alone with its onset
// within 2 s, and the JSON lists the onsets tried.
TEST(Onset, APhaseChangeOfTheProgramDoesNotHideTheOnset) {
  const SyntheticCase c = draw_case(818214, "spool_lag", program_onset_on_other_rig());
  const Diagnosis d = diagnose_case(c);
  ASSERT_TRUE(d.change_point.has_value());
  print_splits(c, d);
  ASSERT_GT(std::abs(d.change_point->t_s - c.onset_s), 8.0)
      << "the strongest split is the onset: the case no longer tests a phase change";
  ASSERT_EQ(causes(d), "spool_lag");
  EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0);
  ASSERT_GE(d.onsets_tried.size(), 2u);
  check_json(d, "model_rig_program_onset",
             "t=[o['t_s'] for o in r['onsets_tried']]; assert len(t)>=2; "
             "assert any(abs(x-r['causes'][0]['onset_s'])<4 for x in t)");
}

// An onset inside a phase whose error no plain split shows: fixed case 818208 of the same run,
// a 9 ms lag of p1's transducer from 84.53 s in a 1.9 Hz sine block (the program holds 37 s,
// sines 61 s, then a triangle and a sweep to 2.9 Hz). Every series split at the sweep's fast
// end (175.5 s, t 48); with the segments' excitation regressed out the errors split at 84.5 s
// (t 21). Was `unexplained`; named alone with its onset within 2 s.
TEST(Onset, AnOnsetInsideASineBlockIsFoundBeyondTheProgramsExcitation) {
  const SyntheticCase c = draw_case(818208, "sensor_lag", program_onset_on_other_rig());
  const Diagnosis d = diagnose_case(c);
  ASSERT_TRUE(d.change_point.has_value());
  print_splits(c, d);
  ASSERT_GT(std::abs(d.change_point->t_s - c.onset_s), 8.0)
      << "the strongest split is the onset: the case no longer tests the excitation";
  ASSERT_EQ(causes(d), "sensor_lag");
  EXPECT_NEAR(d.causes.front().onset_s, c.onset_s, 2.0);
}

// An onset just before a long hold: fixed case 818215 of `model evaluate --programs --rigs other
// --classes onset --seed 818200` (180 s): a supply droop from 88.60 s on a 48 mm rig whose program
// runs steps until 89 s, holds until 150 s and then runs a triangle. The onset search widened
// its window by 8 s at most three times and stopped with the flat stretch still at its edge:
// "from 135.6 s" (121.5-149.7). The window now doubles on, up to the capture's ends; named with
// its onset within 2 s (87.53 s, 86.80-88.25) and the stretch reported within 1 s of it.
TEST(Onset, AnOnsetBeforeALongHoldIsSoughtAcrossTheHold) {
  const SyntheticCase c = draw_case(818215, "supply_droop", program_onset_on_other_rig());
  const Diagnosis d = diagnose_case(c);
  ASSERT_TRUE(d.change_point.has_value());
  print_splits(c, d);
  ASSERT_EQ(causes(d), "supply_droop");
  const auto& cause = d.causes.front();
  std::printf("  onset %.2f s, between %.2f and %.2f s\n", cause.onset_s, cause.onset_earliest_s,
              cause.onset_latest_s);
  EXPECT_NEAR(cause.onset_s, c.onset_s, 2.0);
  EXPECT_LE(cause.onset_earliest_s, c.onset_s + 1.0);
  EXPECT_GE(cause.onset_latest_s, c.onset_s - 1.0);
}

// A constant effect is not said to start where a program's first phase barely shows it: fixed
// case 818110 of `model evaluate --programs --rigs other --classes library --seed 818100` (180
// s): a 4 ms lag of p1's transducer from the start on an 86 mm rig whose program opens with 41 s
// of slow triangle. Named "from 38.8 s": the lag's model started each segment from a pressure
// corrected by tau times a central difference of the noisy readings, which in the slow phase
// cost more than the lag explained, so the fit without the lag there (the onset variant) won.
// The slope is now a five-point least-squares one (2.2 x less noise); named from the start,
// within 25 %.
TEST(Onset, AConstantEffectUnderAQuietFirstPhaseIsNotSaidToStart) {
  CaseSettings settings = other_rig(180.0);
  settings.program = true;
  const SyntheticCase c = draw_case(818110, "sensor_lag", settings);
  ASSERT_EQ(c.onset_s, 0.0);
  const Diagnosis d = diagnose_case(c);
  std::printf("%s\n", sim::describe(c.told).c_str());
  ASSERT_EQ(causes(d), "sensor_lag");
  EXPECT_EQ(d.causes.front().onset_s, 0.0);
  EXPECT_NEAR(d.causes.front().params.front().value, c.main_value, 0.25 * c.main_value);
}

// A spectral line that passes its test but whose ripple fit gains nothing is never named ahead
// of an effect that explains the data: a fixed case of `model evaluate --rigs other` (seed
// 732024, 180 s: a 4.7e-13 leak on a 36 mm rig whose p1 + p2 shows a line at z 5.1), named
// supply_ripple (score 0.001) first and the leak (score 0.99) second before the fix. Fixed,
// not drawn: the case is the one the evaluation found, and its line must pass for the test
// to mean anything (asserted).
TEST(RippleLine, NeverNamedAheadOfAStrongerEffect) {
  const SyntheticCase c = draw_case(732024, "internal_leakage", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_TRUE(d.ripple_line_significant) << "the case no longer has a line: pick another";
  ASSERT_FALSE(d.causes.empty());
  EXPECT_EQ(d.causes.front().effect, "internal_leakage") << causes(d);
  for (const auto& cause : d.causes) EXPECT_NE(cause.effect, "supply_ripple") << causes(d);
  EXPECT_NEAR(d.causes.front().params.front().value, c.main_value, 0.25 * c.main_value);
}

// A library effect hidden on another rig told its description is found, and found alone: no
// second effect next to it, no rig_parameter, its main parameter within 25 %. One case each of
// the leak, the valve bias and the dead band (effects whose size is certain on any rig).
// Fixed cases by default, so that CI cannot flake: the first of each effect in a fresh
// `model evaluate --rigs other --classes library --seed 782000` run (180 s; all three named
// alone there). Drawn afresh each run this test failed in about 1 run in 100 (seed
// 253715682021678798: a leak the capture does not show, a bias on a 106 kg rig whose
// calibration stays far above the true model, a dead band named with entrained air;
// docs/model-check.md). LEAKMON_TEST_SEED=S draws three fresh cases S, S+1, S+2 to explore;
// a drawn effect the capture does not show (the calibrated nominal model already predicts the
// held-out data within 10 % of the generator's true model: nothing is left to name, docs'
// "the capture does not show it") is reported and left out, every other one must pass.
TEST(OtherRig, HiddenEffectIsNamedAlone) {
  const char* effects[] = {"internal_leakage", "valve_bias", "valve_overlap"};
  std::uint64_t seeds[] = {782000, 782005, 782004};
  if (std::getenv("LEAKMON_TEST_SEED")) {
    const auto first = test::model_test_seed("OtherRig.HiddenEffectIsNamedAlone");
    for (std::uint64_t i = 0; i < 3; ++i) seeds[i] = first + i;
  }
  int shown = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const CaseOutcome o = evaluate_case(seeds[i], effects[i], other_rig(180.0));
    std::printf(
        "  seed %llu: %s %s true %.4g est %.4g -> [%s]; NRMSE %.4f -> %.4f, true model "
        "%.4f, floor %.4f; %s\n",
        static_cast<unsigned long long>(seeds[i]), effects[i], o.main_parameter.c_str(),
        o.true_value, o.estimate, o.causes.c_str(), o.nrmse_before, o.nrmse_after, o.nrmse_true,
        o.nrmse_floor, o.rig.c_str());
    EXPECT_TRUE(o.rig_findings.empty()) << "seed " << seeds[i];
    if (o.nrmse_before <= 1.1 * o.nrmse_true) {
      std::printf("  seed %llu: the capture does not show the %s; left out\n",
                  static_cast<unsigned long long>(seeds[i]), effects[i]);
      continue;
    }
    ++shown;
    EXPECT_TRUE(o.only_truth_named()) << "seed " << seeds[i] << ": " << o.causes;
    EXPECT_TRUE(o.parameter_within(0.25))
        << "seed " << seeds[i] << ": " << o.estimate << " for " << o.true_value;
  }
  EXPECT_GE(shown, 1) << "no drawn effect shows in its capture: draw others";
}

// Healthy rig 770009 of `model evaluate --rigs other --classes clean` (59 mm, 20 kg, a slow
// 18.8 ms spool, the stated beta 15 % below the true one): its lightly damped hydraulic mode,
// rung in the pressures, is matched only by a beta within a few per cent of the true one.
// From every start the fit damped the mode out instead (b on its upper bound) and stopped at
// 1.2 x the true model's held-out error (`unexplained`); beta is now scanned on a grid when
// the nominal calibration ends on a bound (model/calibration_fit.hpp, best_beta_on_grid).
TEST(OtherRig, LightlyDampedModeIsMatchedNotDampedOut) {
  const CaseOutcome o = evaluate_case(770009, "none", other_rig(180.0));
  std::printf("  770009: -> %s; NRMSE %.4f, true model %.4f, floor %.4f; %s\n", o.named.c_str(),
              o.nrmse_before, o.nrmse_true, o.nrmse_floor, o.rig.c_str());
  EXPECT_EQ(o.named, "none") << o.causes;
  EXPECT_LT(o.nrmse_before, 1.05 * o.nrmse_true);
}

// A healthy rig whose own lightly damped hydraulic mode, rung by the spool flow noise, shows
// as a line in p1 + p2 that passes the ripple's line test: a fixed case of `model evaluate
// --rigs other` (seed 732007, 180 s, the mode near 73 Hz, b 61 N s/m). The ripple fitted to
// that line gained 0.0004 at t 0.4 and was named on its line test alone before the fix; now
// it needs the held-out evidence of any effect. Fixed, not drawn: the line must pass for the
// test to mean anything (asserted).
TEST(RippleLine, AHealthyRigsOwnModeIsNoRipple) {
  const SyntheticCase c = draw_case(732007, "none", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_TRUE(d.ripple_line_significant) << "the case no longer has a line: pick another";
  for (const auto& cause : d.causes) EXPECT_NE(cause.effect, "supply_ripple") << causes(d);
  EXPECT_EQ(d.cause, "none") << causes(d);
}

// A first cause whose model leaves a calibrated value on its bound is refitted from starts
// across the calibration's bands before further effects are tried: a fixed case of `model
// evaluate --rigs other` (seed 732002, 180 s: an 8.7e-13 external leak on a 4.5 kg rig),
// named external_leakage + supply_droop + sensor_offset with Kv on its bound before the fix,
// the leak alone after it.
TEST(OtherRig, CalibrationOnItsBoundIsRefittedBeforeAnotherEffect) {
  const SyntheticCase c = draw_case(732002, "external_leakage", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  ASSERT_EQ(d.causes.size(), 1u) << causes(d);
  EXPECT_EQ(d.causes.front().effect, "external_leakage");
  EXPECT_NEAR(d.causes.front().params.front().value, c.main_value, 0.25 * c.main_value);
}

// Healthy rigs whose calibrated nominal model stayed above the noise floor: fixed cases of
// `model evaluate --rigs other --classes clean` (180 s). 770007 (26 mm bore, 35 kg, 468 kN/m)
// and 770013 (54 mm, 265 kg): fitted on 24 segments the calibration reached the same point from
// every start, the true values included, and scored 1.4 and 1.25 x the true model's held-out
// error (`unexplained`); on 48 it reaches the true model. 761025 (81 mm, 2.4 kg, Kv 2.85e-6):
// its pressures follow the spool flow noise up to hundreds of hertz, and the floor drawn at
// 0.5 ms came out at 0.68 of the true model's score (`unexplained`). 812000 (97 mm, 211 kg,
// Kv 3.1e-6) hunts at its ~100 Hz hydraulic mode, which no start velocity read off x follows:
// the floor, whose guess started at the capture's estimate, came out at 0.42 of what the true
// model scores (`unexplained`) until its truth ran in before the start (segment_predictor.cpp).
TEST(OtherRig, HealthyRigsTheCalibrationOrTheFloorMissedAreNone) {
  for (const std::uint64_t seed : {770007u, 770013u, 761025u, 812000u}) {
    const Diagnosis d = diagnose_case(draw_case(seed, "none", other_rig(180.0)));
    EXPECT_EQ(d.cause, "none") << "seed " << seed << ": " << causes(d);
    EXPECT_LT(d.nrmse_before, 1.3 * d.nrmse_floor) << "seed " << seed;
  }
}

// A heavy rig whose calibrated bulk modulus came out low (812017 of `model evaluate --rigs other
// --classes clean`: 43 mm bore, 104 kg, 10.4 MPa; beta fitted 24 % low). The floor's draws from
// that soft model rang about half as much as the capture's pressures (mean square), inside the
// old tolerance of a factor of 2, so the floor stayed at the soft model's (0.018 against the
// 0.053 that the true model scores) and a Coulomb friction (score 0.17, t 8) was named. A
// factor of 1.5 matches the ringing: the floor is drawn at a bulk modulus near the true one.
TEST(OtherRig, AFloorRingingFarLessThanTheCaptureIsDrawnAtTheMatchedBeta) {
  const SyntheticCase c = draw_case(812017, "none", other_rig(180.0));
  const Diagnosis d = diagnose_case(c);
  const double ratio = d.floor_ringing.drawn / d.floor_ringing.measured;
  std::printf("  ringing drawn / measured %.3f, floor beta %.3g, true beta %.3g\n", ratio,
              d.floor_beta, c.scenario.params.beta);
  EXPECT_LT(ratio, 1.0 / DiagnosisSettings{}.ringing_tolerance);
  EXPECT_GT(ratio, 0.5);  // inside the old tolerance: the case this test is for
  EXPECT_NEAR(d.floor_beta, c.scenario.params.beta, 0.15 * c.scenario.params.beta);
  EXPECT_EQ(d.cause, "none") << causes(d);
}

// Heavy rigs' segment starts at their true velocity: fixed cases of `model evaluate --rigs other
// --classes clean` (180 s). 812022 (456 kg; its hydraulic mode near 17 Hz) and 812002 (93 kg)
// were `unexplained` and `sensor_lag`: the +-3-sample velocity line read the mode's motion 5 %
// low, every simulated segment started too slow, and the force balance's mass came out 3.4 %
// high to match; the true model itself scored 0.0096 in p with every noise switched off. With
// the cubic velocity (model/piston_velocity.hpp) both are `none` and the mass is the true one.
TEST(OtherRig, HeavyRigsSegmentsStartAtTheirTrueVelocity) {
  for (const std::uint64_t seed : {812022u, 812002u}) {
    const SyntheticCase c = draw_case(seed, "none", other_rig(180.0));
    const Diagnosis d = diagnose_case(c);
    EXPECT_EQ(d.cause, "none") << "seed " << seed << ": " << causes(d);
    const double m = c.scenario.params.m;
    std::printf("  seed %llu: force balance m %.2f kg, true %.2f kg\n",
                static_cast<unsigned long long>(seed), d.force_balance.m, m);
    EXPECT_NEAR(d.force_balance.m, m, 0.02 * m) << "seed " << seed;
  }
}

// A healthy rig whose pressures overshoot past their transducer's range (812008 of `model
// evaluate --rigs other --classes clean`: 28 mm bore, 128 kg, no spring, 16.5 MPa on a 20.7 MPa
// transducer): p1 and p2 sit at the top code on about 80 samples each. The model knows no
// range and predicted the overshoots in full, which took an internal leak to explain (C_L
// fitted, 0.063 -> 0.062). Left out like gaps, the rig is `none`, and the report says why.
TEST(OtherRig, PressuresClippedAtTheirTransducersTopAreLeftOut) {
  const SyntheticCase c = draw_case(812008, "none", other_rig(180.0));
  const MeasuredRecord record = measured_record(simulate_case(c));
  ASSERT_EQ(record.censored.size(), 2u);
  const double top = c.scenario.sensors.pressure_full_scale * (1.0 - 1.0 / 4096.0);
  for (const auto& censored : record.censored) {
    EXPECT_EQ(censored.reason, MeasuredRecord::Censored::Reason::range_end) << censored.channel;
    EXPECT_NEAR(censored.value, top, 1.0) << censored.channel;
    EXPECT_GT(censored.samples, 20u) << censored.channel;
  }
  const Diagnosis d = diagnose(record, c.told);
  EXPECT_EQ(d.cause, "none") << causes(d);
  const std::string dir = test::scratch_dir("model_rig_clipped");
  write_report(dir, record, d);
  std::ostringstream text_stream;
  text_stream << std::ifstream(dir + "/report.md").rdbuf();
  const std::string text = text_stream.str();
  EXPECT_NE(text.find("p1 sits at its largest reading"), std::string::npos) << text;
  EXPECT_NE(text.find("range end"), std::string::npos) << text;
}

// MODEL.md's sensor faults inside a capture of the paper's rig: p1 frozen for 3 s, p2 dropped
// out to 0 for 3 s, x frozen for 3 s, p1 saturated at its top for 3 s, spikes on p2 all along.
// Each held run is left out like a gap and each spike replaced by its neighbours' median; the
// healthy rig is `none` and the leaking one is the leak. Without that, p2 at 0 for 3 s alone
// made the healthy rig `unexplained` at 0.27 against a floor of 0.005, p1 frozen 0.0093, and
// the spikes alone 0.0067 against 0.0045.
TEST(SensorFaults, HeldRunsAreLeftOutAndNeitherHideNorMakeACause) {
  using Kind = sim::SensorFault::Kind;
  using sim::SensorChannel;
  for (const std::string effect : {"none", "internal_leakage"}) {
    CaseSettings settings;
    settings.duration_s = 180.0;
    SyntheticCase c = draw_case(700001, effect, settings);
    c.scenario.faults = {sim::SensorFault{Kind::frozen, SensorChannel::p1, 30.0, 3.0},
                         sim::SensorFault{Kind::dropout, SensorChannel::p2, 70.0, 3.0},
                         sim::SensorFault{Kind::frozen, SensorChannel::x, 110.0, 3.0},
                         sim::SensorFault{Kind::saturated, SensorChannel::p1, 150.0, 3.0},
                         sim::SensorFault{Kind::spikes, SensorChannel::p2, 0.0, 180.0}};
    const MeasuredRecord record = measured_record(simulate_case(c));
    std::size_t left_out = 0;
    std::size_t spikes = 0;
    for (const auto& censored : record.censored) {
      if (censored.reason == MeasuredRecord::Censored::Reason::spikes) {
        EXPECT_EQ(censored.channel, "p2");
        spikes += censored.samples;
      } else {
        EXPECT_EQ(censored.reason, MeasuredRecord::Censored::Reason::held) << censored.channel;
        left_out += censored.samples;
      }
    }
    EXPECT_EQ(record.censored.size(), 4u);  // p1 (two runs), p2, x held; p2's spikes
    EXPECT_GE(left_out, 4u * 1500u);
    EXPECT_LE(left_out, 4u * 1500u + 40u);  // a run may start on the value held before it
    // 4 a minute (Poisson) for 180 s, less those inside the held runs.
    EXPECT_GE(spikes, 3u);
    EXPECT_LE(spikes, 25u);
    const Diagnosis d = diagnose(record, c.told);
    std::printf("  %s with faults -> %s (NRMSE %.4f -> %.4f, floor %.4f)\n", effect.c_str(),
                causes(d).c_str(), d.nrmse_before, d.nrmse_after, d.nrmse_floor);
    EXPECT_EQ(d.cause, effect) << causes(d);
  }
}

}  // namespace
}  // namespace leakmon::model
