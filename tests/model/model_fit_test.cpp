// The model check's own actuator model against the simulator's plant (two implementations of
// MODEL.md must give the same trajectories), and calibration on simulated "measured" data.
#include <gtest/gtest.h>

#include <cstdio>

#include <cmath>
#include <string>

#include "model/actuator_model.hpp"
#include "model/calibration_fit.hpp"
#include "model/diagnosis.hpp"
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

// Each run draws ten random cases. Kv is pinned down in every draw. beta, m and b trade off
// against each other (together they set the hydraulic mode's frequency and damping), and in
// about one draw in ten the fit slides along that valley: one of them lands outside its band
// (m or b sometimes on its bound) or the held-out error rises past 0.03. So those are required
// in at least seven of the ten draws rather than in every one; docs/model-check.md reports it.
TEST(Calibration, RecoversPerturbedParametersFromNoisyData) {
  const auto first_seed =
      test::model_test_seed("Calibration.RecoversPerturbedParametersFromNoisyData");
  constexpr int kDraws = 10;
  int good = 0;
  for (int i = 0; i < kDraws; ++i) {
    const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(i);
    const SyntheticCase c = draw_case(seed, "none", {24.0});
    const MeasuredRecord record = measured_record(simulate_case(c));
    const SegmentPredictor predictor(record);
    const auto segments = spread(split_record(record).fitting, 16);
    const FitResult fit = fit_model(predictor, segments, nullptr, Calibration{});
    const auto& truth = c.scenario.params;
    const auto& fitted = fit.parameters.calibration;
    EXPECT_NEAR(fitted.Kv, truth.Kv, 0.03 * truth.Kv) << "seed " << seed;
    const auto held_out = spread(split_record(record).held_out, 16);
    const double nrmse = predictor.nrmse(fit.parameters, held_out);
    const bool ok = std::abs(fitted.beta - truth.beta) <= 0.25 * truth.beta &&
                    std::abs(fitted.m - truth.m) <= 0.2 * truth.m &&
                    std::abs(fitted.b - truth.b) <= 0.5 * truth.b && nrmse < 0.03;
    std::printf(
        "  seed %llu: beta %.3g (true %.3g)  m %.2f (true %.2f)  b %.0f (true %.0f)  "
        "held-out nrmse %.4f %s\n",
        static_cast<unsigned long long>(seed), fitted.beta, truth.beta, fitted.m, truth.m, fitted.b,
        truth.b, nrmse, ok ? "" : "<- loose");
    if (ok) ++good;
  }
  EXPECT_GE(good, 7)
      << "beta within 25 %, m within 20 %, b within 50 % and held-out NRMSE < 0.03 in " << good
      << " of " << kDraws << " draws";
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
  EXPECT_LT(d.nrmse_after, 0.5 * d.nrmse_before);
  EXPECT_EQ(d.ranking.size(), 11u);
}

}  // namespace
}  // namespace leakmon::model
