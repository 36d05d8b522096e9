// The model check's own actuator model against the simulator's plant (two implementations of
// MODEL.md must give the same trajectories), and calibration on simulated "measured" data.
#include <gtest/gtest.h>

#include <cstdio>

#include <cmath>
#include <string>

#include "model/actuator_model.hpp"
#include "model/calibration_fit.hpp"
#include "model/diagnosis.hpp"
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
  v = {"sensor_lag", {}, {}};
  v.sim_effects.sensor_lag = sim::SensorLag{0.008, sim::PressureChannel::p2};
  v.effects.tau_s = 0.008;
  v.effects.lag_channel = PressureChannel::p2;
  out.push_back(v);
  return out;
}

// Open loop from rest under a slow sinusoidal command, noise off: both implementations of
// MODEL.md must agree to well below the sensor noise.
TEST(ActuatorModel, MatchesTheSimulatorsPlantForEveryEffect) {
  for (const auto& variant : variants()) {
    sim::Parameters sp = sim::Parameters::nominal();
    sp.sigma_w = 0.0;
    sim::Plant plant(sp, variant.sim_effects, 1);
    plant.reset();
    ModelParameters mp;
    mp.effects = variant.effects;
    const ActuatorModel model(mp);
    ActuatorState s;
    s.p1 = s.p2 = s.s = (17.2e6 + 0.1e6) / 2.0;
    const double dt = 0.002;
    double worst_x = 0.0, worst_p = 0.0;
    for (int k = 0; k < 500; ++k) {
      const double t = k * dt;
      const double u = 1.5 * std::sin(2.0 * 3.14159265358979 * 1.5 * t);
      plant.advance(u, t, dt);
      model.advance(s, u, t, dt);
      const Reading r = model.read(s);
      worst_x = std::max(worst_x, std::abs(r.x - plant.state().x));
      worst_p = std::max(worst_p, std::abs(r.p1 - plant.state().p1_transducer));
      worst_p = std::max(worst_p, std::abs(r.p2 - plant.state().p2_transducer));
    }
    EXPECT_LT(worst_x, 5e-6) << variant.name;  // position noise is 5 um
    EXPECT_LT(worst_p, 5e3) << variant.name;   // pressure noise is 5 kPa
  }
}

// m from the measured force balance (force_balance.hpp), on fresh random cases: clean ones,
// and the effects that act on the piston or on one pressure reading (the regression's
// friction, constant and pressure-change terms exist for them). A clean capture must give a
// usable estimate with m within 10 %; with an effect, any estimate that calls itself usable
// must have m within 20 % (seen: +11.6 % with a pressure-transducer offset, -9 % under strong
// Coulomb friction; the calibration refits beta and b around it, and on these 24 s captures
// strong friction can make it unusable: diagnose() then fits m). b, only a starting point for
// the calibration, must merely be in the right range.
TEST(ForceBalance, RecoversMassAndDampingFromMeasuredSignals) {
  const auto first_seed =
      test::model_test_seed("ForceBalance.RecoversMassAndDampingFromMeasuredSignals");
  const std::vector<std::string> effects = {"none",          "none",       "coulomb_friction",
                                            "sensor_offset", "sensor_lag", "internal_leakage"};
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const std::uint64_t seed = first_seed + i;
    const SyntheticCase c = draw_case(seed, effects[i], {24.0});
    const MeasuredRecord record = measured_record(simulate_case(c));
    const ForceBalance fb = estimate_force_balance(record, split_record(record).fitting);
    const auto& truth = c.scenario.params;
    std::printf("  %-16s seed %llu: m %.2f (true %.2f)  b %.0f (true %.0f)%s\n", effects[i].c_str(),
                static_cast<unsigned long long>(seed), fb.m, truth.m, fb.b, truth.b,
                usable(fb) ? "" : "  (not usable)");
    if (effects[i] == "none") {
      EXPECT_TRUE(usable(fb)) << "seed " << seed;
    }
    if (!usable(fb)) continue;
    const double m_band = effects[i] == "none" ? 0.1 : 0.2;
    EXPECT_NEAR(fb.m, truth.m, m_band * truth.m) << effects[i] << " seed " << seed;
    EXPECT_NEAR(fb.b, truth.b, 0.5 * truth.b) << effects[i] << " seed " << seed;
  }
}

// Each run draws ten random cases: m from the force balance, beta, Kv and b fitted by the
// simulation (the way diagnose() calibrates), on 24 s captures. Without the force balance
// beta, m and b traded off along the hydraulic mode's valley (bands of 25 %, 20 % and 50 %
// held in only about 9 draws of 10). With m measured the bands are tighter (beta 20 %, m 10 %,
// b 40 %); on these short captures beta and b can still share the damping (seen: beta +17 %
// with b +30 %), and now and then one held-out segment is mispredicted even with the right
// parameters (held-out NRMSE 0.089 seen; docs/model-check.md), so nine of the ten draws must
// be in the bands with a held-out NRMSE below 0.03, and Kv within 3 % in every draw.
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
    ASSERT_TRUE(usable(fb)) << "seed " << seed;
    Calibration start;
    start.m = fb.m;
    start.b = fb.b;
    FitSettings settings;
    settings.free_calibration = {true, true, false, true};
    const FitResult fit = fit_model(predictor, spread(plan.fitting, 16), nullptr, start, settings);
    const auto& truth = c.scenario.params;
    const auto& fitted = fit.parameters.calibration;
    const double nrmse = predictor.nrmse(fit.parameters, spread(plan.held_out, 16));
    const bool ok = std::abs(fitted.beta - truth.beta) <= 0.2 * truth.beta &&
                    std::abs(fitted.m - truth.m) <= 0.1 * truth.m &&
                    std::abs(fitted.b - truth.b) <= 0.4 * truth.b && nrmse < 0.03;
    std::printf(
        "  seed %llu: beta %.3g (true %.3g)  Kv %.3g (true %.3g)  m %.2f (true %.2f)  b %.0f "
        "(true %.0f)  held-out nrmse %.4f%s\n",
        static_cast<unsigned long long>(seed), fitted.beta, truth.beta, fitted.Kv, truth.Kv,
        fitted.m, truth.m, fitted.b, truth.b, nrmse, ok ? "" : "  <- outside the bands");
    EXPECT_NEAR(fitted.Kv, truth.Kv, 0.03 * truth.Kv) << "seed " << seed;
    if (ok) ++in_bands;
  }
  EXPECT_GE(in_bands, 9) << "beta within 20 %, m within 10 %, b within 40 % and held-out NRMSE "
                            "below 0.03 in "
                         << in_bands << " of " << kDraws << " draws";
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
  EXPECT_NEAR(d.params[0].value, 3e-12, 0.25 * 3e-12);
  // The named cause must predict held-out data better. Halving is the full-size target
  // (measured by `leakmon model evaluate`, met for every named leak there); with 8 fitting and
  // 16 held-out segments of a 24 s capture one mispredicted segment can keep the ratio above
  // one half (seen: 0.167 -> 0.103 with the leak named and C_L within 25 %).
  EXPECT_LT(d.nrmse_after, 0.75 * d.nrmse_before);
  EXPECT_EQ(d.ranking.size(), 11u);
}

}  // namespace
}  // namespace leakmon::model
