// The model check's predictor against the simulator's plant (the same equations, w = 0), and
// calibration on simulated "measured" data.
#include <gtest/gtest.h>

#include <cstdio>

#include <algorithm>
#include <cmath>
#include <string>

#include "model/actuator_model.hpp"
#include "model/calibration_fit.hpp"
#include "model/change_point.hpp"
#include "model/diagnosis.hpp"
#include "model/effect_library.hpp"
#include "model/force_balance.hpp"
#include "model/measured_record.hpp"
#include "model/synthetic_case.hpp"
#include "sim/plant.hpp"
#include "tests/model/test_seed.hpp"

namespace leakmon::model {
namespace {

struct Variant {
  std::string name;
  sim::Effects sim_effects;
  EffectParameters effects;
};

std::vector<Variant> variants() {
  std::vector<Variant> out;
  out.push_back({"nominal", {}, {}});
  Variant v;
  v = {"internal_leakage", {}, {}};
  v.sim_effects.internal_leakage = sim::InternalLeakage{3e-12};
  v.effects.C_L = 3e-12;
  out.push_back(v);
  v = {"external_leakage", {}, {}};
  v.sim_effects.external_leakage = sim::ExternalLeakage{1e-12, 2};
  v.effects.C_E = 1e-12;
  v.effects.external_chamber = 2;
  out.push_back(v);
  v = {"entrained_air", {}, {}};
  v.sim_effects.entrained_air = sim::EntrainedAir{0.1};
  v.effects.alpha = 0.1;
  out.push_back(v);
  v = {"valve_overlap", {}, {}};
  v.sim_effects.valve_overlap = sim::ValveOverlap{0.03};
  v.effects.d = 0.03;
  out.push_back(v);
  v = {"valve_bias", {}, {}};
  v.sim_effects.valve_bias = sim::ValveBias{-0.2};
  v.effects.u0 = -0.2;
  out.push_back(v);
  v = {"spool_lag", {}, {}};
  v.sim_effects.spool_lag = sim::SpoolLag{0.01};
  v.effects.spool_tau = 0.01;
  out.push_back(v);
  v = {"supply_ripple", {}, {}};
  v.sim_effects.supply_ripple = sim::SupplyRipple{8e5, 90.0};
  v.effects.ripple_dP = 8e5;
  v.effects.ripple_f = 90.0;
  out.push_back(v);
  v = {"supply_droop", {}, {}};
  v.sim_effects.supply_droop = sim::SupplyDroop{2e10};
  v.effects.R_s = 2e10;
  out.push_back(v);
  v = {"coulomb_friction", {}, {}};
  v.sim_effects.coulomb_friction = sim::CoulombFriction{150.0};
  v.effects.F_C = 150.0;
  out.push_back(v);
  v = {"sensor_lag", {}, {}};
  v.sim_effects.sensor_lag = sim::SensorLag{0.008, sim::PressureChannel::p2};
  v.effects.tau_s = 0.008;
  v.effects.lag_channel = PressureChannel::p2;
  out.push_back(v);
  return out;
}

// The predictor is the simulator's plant with w = 0: open loop from rest under a slow
// sinusoidal command, the Plant run with sigma_w = 0 and the predictor's sub-step must give
// the same trajectories to rounding (one set of equations, sim/actuator.hpp); with each at its
// own step (the Plant's accuracy-chosen one, the predictor's adaptive count) they must still
// agree to well below the sensor noise.
TEST(ActuatorModel, IsTheSimulatorsPlantWithoutFlowNoise) {
  for (const auto& variant : variants()) {
    sim::Parameters sp = sim::Parameters::nominal();
    sp.sigma_w = 0.0;
    ModelParameters mp;
    mp.effects = variant.effects;
    const ActuatorModel model(mp);
    const double dt = 0.002;
    sim::Plant same_step(sp, variant.sim_effects, 1, dt / model.substeps(dt));
    sim::Plant own_step(sp, variant.sim_effects, 1);
    same_step.reset();
    own_step.reset();
    ActuatorState s;
    s.p1 = s.p2 = s.s = (17.2e6 + 0.1e6) / 2.0;
    double same_x = 0.0, same_p = 0.0, own_x = 0.0, own_p = 0.0;
    for (int k = 0; k < 500; ++k) {
      const double t = k * dt;
      const double u = 1.5 * std::sin(2.0 * 3.14159265358979 * 1.5 * t);
      same_step.advance(u, t, dt);
      own_step.advance(u, t, dt);
      model.advance(s, u, t, dt);
      const Reading r = model.read(s);
      same_x = std::max(same_x, std::abs(r.x - same_step.state().x));
      same_p = std::max(same_p, std::abs(r.p1 - same_step.state().p1_transducer));
      same_p = std::max(same_p, std::abs(r.p2 - same_step.state().p2_transducer));
      own_x = std::max(own_x, std::abs(r.x - own_step.state().x));
      own_p = std::max(own_p, std::abs(r.p1 - own_step.state().p1_transducer));
      own_p = std::max(own_p, std::abs(r.p2 - own_step.state().p2_transducer));
    }
    EXPECT_LT(same_x, 1e-12) << variant.name;  // rounding only
    EXPECT_LT(same_p, 1e-3) << variant.name;
    EXPECT_LT(own_x, 5e-6) << variant.name;  // position noise is 5 um
    EXPECT_LT(own_p, 5e3) << variant.name;   // pressure noise is 5 kPa
  }
}

// Coulomb friction's tanh(v / 1 mm/s) on a light piston is a damper far stiffer than the
// predictor's sub-steps (250 N on 3 kg: 83 000 1/s). The predictor lets the piston stick (its
// velocity slaved to the force friction holds) rather than widening the band, which let it
// creep and put the true friction's prediction 10 kPa rms off the simulator (docs/model-check.md,
// 815002): the prediction must stay well below the 5 kPa sensor noise, under a command that
// makes the piston stick and slip.
TEST(ActuatorModel, ALightPistonUnderCoulombFrictionSticksAsTheSimulatorsDoes) {
  struct Rig {
    double m, F_C;
  };
  for (const Rig rig : {Rig{3.0, 250.0}, Rig{1.0, 100.0}, Rig{10.0, 400.0}, Rig{30.0, 1000.0}}) {
    sim::Parameters sp = sim::Parameters::nominal();
    sp.sigma_w = 0.0;
    sp.m = rig.m;
    sim::Effects effects;
    effects.coulomb_friction = sim::CoulombFriction{rig.F_C};
    ModelParameters mp;
    mp.calibration = {sp.beta, sp.Kv, sp.m, sp.b};
    mp.effects.F_C = rig.F_C;
    const ActuatorModel model(mp, sp);
    sim::Plant plant(sp, effects, 1);
    plant.reset();
    ActuatorState s;
    s.p1 = s.p2 = s.s = (17.2e6 + 0.1e6) / 2.0;
    const double dt = 0.002;
    double sum_x = 0.0, sum_p = 0.0, travel = 0.0;
    const int n = 2000;
    for (int k = 0; k < n; ++k) {
      const double t = k * dt;
      const double u =
          3.0 * std::sin(2.0 * 3.14159265358979 * 0.7 * t) + ((k / 300) % 2 ? 2.0 : -2.0);
      const double x_before = plant.state().x;
      plant.advance(u, t, dt);
      model.advance(s, u, t, dt);
      travel += std::abs(plant.state().x - x_before);
      const Reading r = model.read(s);
      sum_x += std::pow(r.x - plant.state().x, 2);
      sum_p += std::pow(r.p1 - plant.state().p1_transducer, 2);
    }
    const std::string name = "m " + std::to_string(rig.m) + " kg, F_C " + std::to_string(rig.F_C);
    EXPECT_GT(travel, 0.05) << name;                  // it slides, not only sticks
    EXPECT_LT(std::sqrt(sum_x / n), 2.5e-6) << name;  // widened band: 4.6-10 um
    EXPECT_LT(std::sqrt(sum_p / n), 3e3) << name;     // widened band: 5-11 kPa
  }
}

// m from the measured force balance (force_balance.hpp), on fresh random cases: clean ones,
// and the effects that act on the piston or on one pressure reading (the regression's
// friction, constant and pressure-change terms exist for them). A clean capture should give a
// usable estimate with m within 10 % (within 5.5 % in 100 draws, but one clean draw in about
// 400 is unusable, m 14.4 for a true 11.8; and 2 of 304 usable clean draws lay beyond 10 %:
// +11.7 %, and CI's seed 17223480221079556843, +18.7 %, m 10.90 for a true 9.19): so at least
// one of the two clean ones must be usable and within 10 %, and every usable one within 20 %
// (both beyond 10 %: about 1 run in 20000). With an effect, any estimate that calls itself
// usable must have m within 20 % (seen: +11.6 % with a pressure-transducer offset, -15 to +12 %
// under strong Coulomb friction, see the next test; the calibration refits beta and b around it,
// and on these 24 s captures strong friction can make it unusable: diagnose() then fits m). b, only
// a starting point for the calibration, must merely be in the right range (clean: within 19 % in
// 100 draws).
TEST(ForceBalance, RecoversMassAndDampingFromMeasuredSignals) {
  const auto first_seed =
      test::model_test_seed("ForceBalance.RecoversMassAndDampingFromMeasuredSignals");
  const std::vector<std::string> effects = {"none",          "none",       "coulomb_friction",
                                            "sensor_offset", "sensor_lag", "internal_leakage"};
  int clean_usable = 0, clean_within_10 = 0;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const std::uint64_t seed = first_seed + i;
    const SyntheticCase c = draw_case(seed, effects[i], {24.0});
    const MeasuredRecord record = measured_record(simulate_case(c));
    const ForceBalance fb = estimate_force_balance(record, split_record(record).fitting);
    const auto& truth = c.scenario.params;
    std::printf("  %-16s seed %llu: m %.2f (true %.2f)  b %.0f (true %.0f)%s\n", effects[i].c_str(),
                static_cast<unsigned long long>(seed), fb.m, truth.m, fb.b, truth.b,
                usable(fb) ? "" : "  (not usable)");
    if (effects[i] == "none" && usable(fb)) {
      ++clean_usable;
      clean_within_10 += std::abs(fb.m - truth.m) <= 0.1 * truth.m;
    }
    // A lagged pressure reading delays the measured force: the regression reads it as less
    // damping (b 63 % low seen in 50 draws) and now and then as more mass (m +35 % in one of
    // 60 draws, called usable). Under a sensor lag neither is a measurement, only a start
    // (docs/model-check.md, known weak spots).
    if (!usable(fb) || effects[i] == "sensor_lag") continue;
    EXPECT_NEAR(fb.m, truth.m, 0.2 * truth.m) << effects[i] << " seed " << seed;
    EXPECT_NEAR(fb.b, truth.b, 0.5 * truth.b) << effects[i] << " seed " << seed;
  }
  EXPECT_GE(clean_usable, 1) << "neither clean capture gave a usable force balance";
  EXPECT_GE(clean_within_10, 1) << "neither clean capture gave m within 10 %";
}

// The friction regressor reads the sign of v off the +-3-sample line, not the cubic of the
// segment starts: with the cubic, 40 fixed draws with Coulomb friction (24 s, as above) gave
// the mass +11 % in the median and beyond 20 % on 17 of 87 usable draws (CI's failing draw
// 4113666562347060725: +20.1 %); with the line, +1 % and none beyond 14 %.
TEST(ForceBalance, CoulombFrictionLeavesTheMassUnbiased) {
  std::vector<double> errors;
  for (std::uint64_t seed = 900000; seed < 900040; ++seed) {
    const SyntheticCase c = draw_case(seed, "coulomb_friction", {24.0});
    const MeasuredRecord record = measured_record(simulate_case(c));
    const ForceBalance fb = estimate_force_balance(record, split_record(record).fitting);
    if (!usable(fb)) continue;
    errors.push_back(fb.m / c.scenario.params.m - 1.0);
    EXPECT_LT(std::abs(errors.back()), 0.2) << "seed " << seed;
  }
  ASSERT_GE(errors.size(), 30u);
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2),
                   errors.end());
  const double median = errors[errors.size() / 2];
  std::printf("  %zu usable draws, median mass error %+.3f\n", errors.size(), median);
  EXPECT_LT(std::abs(median), 0.04);
}

// Each run draws ten random cases: m from the force balance, beta, Kv and b fitted by the
// simulation (the way diagnose() calibrates), on 24 s captures. What the calibration must
// deliver is a model that predicts unseen data as well as the true parameters do: its
// held-out NRMSE may exceed the truth's by at most half (a held-out segment can be
// mispredicted even with the true parameters, NRMSE 0.05 seen, so an absolute bound would
// test the noise). Beta must be within 20 % and m within 10 %; Kv within 3 % in every draw.
// b is reported, not banded: on 24 s captures the valve's own damping dominates and the cost
// is flat along b (seen: 3.004e-5 at b = 120 against 3.037e-5 at the true 215, with m 1.6 %
// low), so b wanders where it costs nothing. 8 of 300 draws fell outside the bands (beta or
// m 10-23 % high together, the force balance's m error carried into beta), so eight of ten
// must be inside: a run fails by chance about once in 500.
TEST(Calibration, RecoversPerturbedParametersFromNoisyData) {
  const auto first_seed =
      test::model_test_seed("Calibration.RecoversPerturbedParametersFromNoisyData");
  constexpr int kDraws = 10;
  int in_bands = 0;
  for (int i = 0; i < kDraws; ++i) {
    const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(i);
    const SyntheticCase c = draw_case(seed, "none", {24.0});
    const MeasuredRecord record = measured_record(simulate_case(c));
    const SegmentPredictor predictor(record);
    const SegmentPlan plan = split_record(record);
    const ForceBalance fb = estimate_force_balance(record, plan.fitting);
    // As diagnose() does: m from the force balance when usable, else fitted with the rest.
    Calibration start;
    FitSettings settings;
    if (usable(fb)) {
      start.m = fb.m;
      start.b = fb.b;
      settings.free_calibration = {true, true, false, true};
    }
    const FitResult fit = fit_model(predictor, spread(plan.fitting, 16), nullptr, start, settings);
    const auto& truth = c.scenario.params;
    const auto& fitted = fit.parameters.calibration;
    ModelParameters true_model;
    true_model.calibration = {truth.beta, truth.Kv, truth.m, truth.b};
    const auto held_out = spread(plan.held_out, 16);
    const double nrmse = predictor.nrmse(fit.parameters, held_out);
    const double nrmse_truth = predictor.nrmse(true_model, held_out);
    const bool ok = std::abs(fitted.beta - truth.beta) <= 0.2 * truth.beta &&
                    std::abs(fitted.m - truth.m) <= 0.1 * truth.m && nrmse <= 1.5 * nrmse_truth;
    std::printf(
        "  seed %llu: beta %.3g (true %.3g)  Kv %.3g (true %.3g)  m %.2f (true %.2f)  b %.0f "
        "(true %.0f)  held-out nrmse %.4f (true parameters %.4f)%s\n",
        static_cast<unsigned long long>(seed), fitted.beta, truth.beta, fitted.Kv, truth.Kv,
        fitted.m, truth.m, fitted.b, truth.b, nrmse, nrmse_truth,
        ok ? "" : "  <- outside the bands");
    EXPECT_NEAR(fitted.Kv, truth.Kv, 0.03 * truth.Kv) << "seed " << seed;
    if (ok) ++in_bands;
  }
  EXPECT_GE(in_bands, 8) << "beta within 20 %, m within 10 % and held-out NRMSE within 1.5x the "
                            "true parameters' in "
                         << in_bands << " of " << kDraws << " draws";
}

// A calibrated value the data push beyond its bound is held there by a clamp, which has no
// gradient: Gauss-Newton gave it a standard error of zero, and the drift test then called any
// difference to it significant (docs/model-check.md, seed 796000). Its error is the profile's
// curvature (how well the data pin it), not the clamp's zero: about the error the same data
// give it where the bound does not bite, within 3 x either way (seen: 0.57-1.10 x over the
// residuals' RMS in 16 draws; the clamp gave 0, the whole band would be about 1000 x). Kv, the
// value the data pin best (within 3 % above), is stated 30 % high, so that its lower bound (-20 %)
// lies 4 % above the rig's own, and then as it is.
TEST(Calibration, ValueOnItsBoundHasTheProfilesErrorNotZero) {
  const auto seed = test::model_test_seed("Calibration.ValueOnItsBoundHasTheProfilesErrorNotZero");
  const SyntheticCase c = draw_case(seed, "none", {24.0});
  const MeasuredRecord record = measured_record(simulate_case(c));
  const SegmentPredictor predictor(record);
  const auto segments = spread(split_record(record).fitting, 16);
  FitSettings settings;
  settings.uncertainties = true;
  settings.stated = Calibration::of(c.scenario.params);
  const FitResult inside = fit_model(predictor, segments, nullptr, settings.stated, settings);
  settings.stated.Kv *= 1.3;
  const FitResult held = fit_model(predictor, segments, nullptr, settings.stated, settings);
  const auto on_bound = calibration_at_bound(held.parameters.calibration, settings.stated);
  std::printf(
      "  seed %llu: Kv %.4g +- %.3g inside the bounds, %.4g +- %.3g on the lower bound "
      "%.4g (true %.4g)\n",
      static_cast<unsigned long long>(seed), inside.parameters.calibration.Kv,
      inside.calibration_errors.Kv, held.parameters.calibration.Kv, held.calibration_errors.Kv,
      calibration_bounds(settings.stated).first.Kv, c.scenario.params.Kv);
  ASSERT_NE(std::find(on_bound.begin(), on_bound.end(), "Kv"), on_bound.end())
      << "Kv is not on its bound: the case tests nothing";
  ASSERT_GT(inside.calibration_errors.Kv, 0.0);
  // The fit held off its optimum leaves a larger residual variance, which every error scales
  // with: the curvatures are compared, the error over the residuals' RMS.
  const double ratio = held.calibration_errors.Kv / std::sqrt(held.cost) /
                       (inside.calibration_errors.Kv / std::sqrt(inside.cost));
  std::printf("  residual variance x %.2f; error over the residuals' RMS x %.2f\n",
              held.cost / inside.cost, ratio);
  EXPECT_GT(ratio, 1.0 / 3.0);
  EXPECT_LT(ratio, 3.0);
}

// fit_model answers the solver's repeated requests for a point (the Jacobian's base, the
// optimum's residuals and Jacobian) from the evaluations it kept: the fit must be the one
// that simulates every request, bit for bit, on the path with the most repeats (an effect
// candidate, errors asked for, Kv held on its bound so that the profile's refits run too).
TEST(Calibration, ReusedEvaluationsGiveTheFitOfFreshOnes) {
  const auto seed = test::model_test_seed("Calibration.ReusedEvaluationsGiveTheFitOfFreshOnes");
  const SyntheticCase c = draw_case(seed, "internal_leakage", {24.0});
  const MeasuredRecord record = measured_record(simulate_case(c));
  const SegmentPredictor predictor(record);
  const auto segments = spread(split_record(record).fitting, 8);
  const auto library = effect_library(0.0);
  const auto leak = std::find_if(library.begin(), library.end(), [](const EffectCandidate& e) {
    return e.effect == "internal_leakage";
  });
  ASSERT_NE(leak, library.end());
  FitSettings settings;
  settings.uncertainties = true;
  settings.stated = Calibration::of(c.scenario.params);
  settings.stated.Kv *= 1.3;
  FitSettings fresh = settings;
  fresh.reuse_evaluations = false;
  const FitResult reused = fit_model(predictor, segments, &*leak, settings.stated, settings);
  const FitResult simulated = fit_model(predictor, segments, &*leak, settings.stated, fresh);
  const auto on_bound = calibration_at_bound(reused.parameters.calibration, settings.stated);
  std::printf("  seed %llu: %zu values on their bounds, cost %.6g, %d evaluations\n",
              static_cast<unsigned long long>(seed), on_bound.size(), reused.cost,
              reused.evaluations);
  EXPECT_FALSE(on_bound.empty()) << "no profile refits: only the solver's repeats are tested";
  const auto same_calibration = [](const Calibration& a, const Calibration& b) {
    EXPECT_EQ(a.beta, b.beta);
    EXPECT_EQ(a.Kv, b.Kv);
    EXPECT_EQ(a.m, b.m);
    EXPECT_EQ(a.b, b.b);
  };
  same_calibration(reused.parameters.calibration, simulated.parameters.calibration);
  same_calibration(reused.calibration_errors, simulated.calibration_errors);
  EXPECT_EQ(reused.parameters.effects.C_L, simulated.parameters.effects.C_L);
  EXPECT_EQ(reused.values, simulated.values);
  EXPECT_EQ(reused.value_errors, simulated.value_errors);
  EXPECT_EQ(reused.cost, simulated.cost);
  EXPECT_EQ(reused.evaluations, simulated.evaluations);
}

// A Jacobian column of an effect that starts inside the capture simulates only the segments
// that reach its onset: the fit must be the one that simulates every segment for every column,
// bit for bit, for a joint candidate whose parts act from the start (a friction) and from an
// onset (a leak from 12 s of 24), with errors asked for (the optimum's Jacobian too).
TEST(Calibration, SkippingSegmentsBeforeAnOnsetGivesTheFitOfSimulatingThemAll) {
  const auto seed = test::model_test_seed(
      "Calibration.SkippingSegmentsBeforeAnOnsetGivesTheFitOfSimulatingThemAll");
  const SyntheticCase c = draw_case(seed, "internal_leakage", {24.0});
  const MeasuredRecord record = measured_record(simulate_case(c));
  const SegmentPredictor predictor(record);
  const auto segments = spread(split_record(record).fitting, 8);
  const auto library = effect_library(0.0);
  const auto find = [&](const std::string& name) {
    const auto it = std::find_if(library.begin(), library.end(),
                                 [&](const EffectCandidate& e) { return e.effect == name; });
    EXPECT_NE(it, library.end()) << name;
    return *it;
  };
  EffectCandidate leak = find("internal_leakage");
  leak.onset_s = 12.0;
  const EffectCandidate joint = combine({find("coulomb_friction"), leak});
  std::size_t before = 0, after = 0;
  for (const auto& seg : segments) {
    (predictor.reaches(seg, leak.onset_s) ? after : before) += 1;
  }
  std::printf("  seed %llu: %zu segments end before the onset, %zu reach it\n",
              static_cast<unsigned long long>(seed), before, after);
  ASSERT_GT(before, 0u) << "no segment is skipped: the case tests nothing";
  ASSERT_GT(after, 0u);
  FitSettings settings;
  settings.uncertainties = true;
  settings.stated = Calibration::of(c.scenario.params);
  FitSettings every = settings;
  every.skip_segments_before_onset = false;
  const FitResult skipped = fit_model(predictor, segments, &joint, settings.stated, settings);
  const FitResult simulated = fit_model(predictor, segments, &joint, settings.stated, every);
  EXPECT_EQ(skipped.parameters.calibration.beta, simulated.parameters.calibration.beta);
  EXPECT_EQ(skipped.parameters.calibration.Kv, simulated.parameters.calibration.Kv);
  EXPECT_EQ(skipped.parameters.calibration.m, simulated.parameters.calibration.m);
  EXPECT_EQ(skipped.parameters.calibration.b, simulated.parameters.calibration.b);
  EXPECT_EQ(skipped.values, simulated.values);
  EXPECT_EQ(skipped.value_errors, simulated.value_errors);
  EXPECT_EQ(skipped.cost, simulated.cost);
  EXPECT_EQ(skipped.evaluations, simulated.evaluations);
}

// The predictor keeps the spool positions of its last few spool laws: residuals from a kept
// run must be those of a predictor that has kept nothing, also after the laws kept have been
// replaced (more laws than it keeps, in turn, twice) and with a law switching at an onset.
TEST(SegmentPredictor, KeptSpoolPositionsGiveTheResidualsOfFreshOnes) {
  const auto seed =
      test::model_test_seed("SegmentPredictor.KeptSpoolPositionsGiveTheResidualsOfFreshOnes");
  const SyntheticCase c = draw_case(seed, "spool_lag", {24.0});
  const MeasuredRecord record = measured_record(simulate_case(c));
  const auto segments = spread(split_record(record).fitting, 8);
  std::vector<ModelParameters> laws(6);
  laws[1].effects.spool_tau = 0.02;
  laws[2].effects.u0 = 0.05;
  laws[3].effects.u0 = -0.05;
  laws[4].calibration.Kv *= 1.1;  // the same spool law as laws[0]: a kept run reused
  laws[5].onset_s = 12.0;
  laws[5].effects.spool_tau = 0.02;
  const SegmentPredictor kept(record);
  std::vector<double> from_kept(SegmentPredictor::residual_count(segments));
  std::vector<double> from_fresh(from_kept.size());
  for (int round = 0; round < 2; ++round) {
    for (std::size_t i = 0; i < laws.size(); ++i) {
      kept.residuals(laws[i], segments, from_kept);
      const SegmentPredictor fresh(record);
      fresh.residuals(laws[i], segments, from_fresh);
      EXPECT_EQ(from_kept, from_fresh) << "round " << round << ", law " << i;
    }
  }
}

// The onset search sums the errors over the segments around each trial onset from two runs
// (the model before the onset throughout and after it throughout) and simulates only the
// segments near the onset for it: the sums must be those of simulating every segment for every
// onset, for effects that switch the spool (a bias, a slower spool), a transducer's reading
// (a lag starting from the pressure it reads) and the flows (a leak).
TEST(SegmentPredictor, OnsetTrialsSummedAroundEachOnsetEqualWholeSimulations) {
  const auto seed = test::model_test_seed(
      "SegmentPredictor.OnsetTrialsSummedAroundEachOnsetEqualWholeSimulations");
  const SyntheticCase c = draw_case(seed, "valve_bias", {24.0});
  const MeasuredRecord record = measured_record(simulate_case(c));
  const SegmentPredictor predictor(record);
  const std::vector<Segment> segments = segments_in_time_order(split_record(record));
  std::vector<ModelParameters> laws(4);
  laws[0].effects.u0 = 0.05;
  laws[1].effects.spool_tau = 0.03;
  laws[2].effects.tau_s = 0.006;
  laws[3].effects.C_L = 2e-12;
  std::vector<double> onsets;
  for (double t = 3.0; t < 21.0; t += 0.37) onsets.push_back(t);
  for (std::size_t i = 0; i < laws.size(); ++i) {
    ModelParameters law = laws[i];
    law.onset_s = 12.0;
    law.before = ModelParameters{}.effects;
    const auto sums = summed_errors_at_onsets(predictor, law, segments, onsets);
    ASSERT_EQ(sums.size(), onsets.size());
    double lowest = sums.front(), highest = sums.front();
    for (std::size_t k = 0; k < onsets.size(); ++k) {
      ModelParameters trial = law;
      trial.onset_s = onsets[k];
      double whole = 0.0;
      for (double e : segment_errors(predictor, trial, segments)) whole += e;
      EXPECT_NEAR(sums[k], whole, 1e-9 * whole) << "law " << i << ", onset " << onsets[k];
      lowest = std::min(lowest, sums[k]);
      highest = std::max(highest, sums[k]);
    }
    // The onset matters: otherwise the test would compare constants.
    EXPECT_GT(highest, 1.001 * lowest) << "law " << i;
  }
}

// The whole workflow on a short capture with a clear leak, cheap enough for the sanitizer
// builds (the full-size random cases are model_diagnosis_test, labelled long).
TEST(Diagnosis, NamesAClearLeakOnAShortCapture) {
  const auto seed = test::model_test_seed("Diagnosis.NamesAClearLeakOnAShortCapture");
  SyntheticCase c = draw_case(seed, "internal_leakage", {24.0});
  c.scenario.effects.internal_leakage->C_L = 3e-12;
  const MeasuredRecord record = measured_record(simulate_case(c));
  DiagnosisSettings settings;
  settings.max_fitting_segments = 8;
  settings.screening_segments = 4;
  settings.max_held_out_segments = 16;
  settings.refined_effects = 2;
  const Diagnosis d = diagnose(record, settings);
  EXPECT_EQ(d.cause, "internal_leakage");
  ASSERT_FALSE(d.params.empty());
  EXPECT_EQ(d.params[0].name, "C_L");
  // 25 % is the full-size target; with 8 fitting segments of 24 s, -28 % was seen in 50 runs.
  EXPECT_NEAR(d.params[0].value, 3e-12, 0.4 * 3e-12);
  // The named cause must predict held-out data better. Halving is the full-size target
  // (measured by `leakmon model evaluate`, met for every named leak there); with 8 fitting and
  // 16 held-out segments of a 24 s capture one mispredicted segment can keep the ratio above
  // one half (seen: 0.167 -> 0.103 with the leak named and C_L within 25 %).
  EXPECT_LT(d.nrmse_after, 0.75 * d.nrmse_before);
  EXPECT_EQ(d.ranking.size(), 11u);
}

}  // namespace
}  // namespace leakmon::model
