// Issue 12's building blocks that need no fitting: the noise floor read off a capture, the
// calibration-bound flags and the joint candidate of the forward selection. Fresh seeds per
// run (printed; LEAKMON_TEST_SEED forces one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "model/calibration_fit.hpp"
#include "model/diagnosis.hpp"
#include "model/effect_library.hpp"
#include "model/misfit.hpp"
#include "model/piston_velocity.hpp"
#include "model/segment_predictor.hpp"
#include "model/synthetic_case.hpp"
#include "tests/model/test_seed.hpp"

namespace leakmon::model {
namespace {

CaseSettings short_case() {
  CaseSettings s;
  s.duration_s = 24.0;
  return s;
}

// The generator's true model on a capture drawn afresh: its held-out NRMSE, and the noise
// floor (mean over x, p1, p2) drawn from it with the diagnosis's own floor settings.
std::pair<double, double> true_model_and_floor(std::uint64_t seed, const CaseSettings& settings) {
  const DiagnosisSettings diagnosis;
  const SyntheticCase c = draw_case(seed, "none", settings);
  const MeasuredRecord record = measured_record(simulate_case(c));
  const SegmentPredictor predictor(record, c.scenario.params);
  const auto plan = split_record(record);
  const ModelParameters truth = true_model(c);
  const double achieved = predictor.nrmse(truth, plan.held_out);
  const auto floor =
      predictor.noise_floor(truth, plan.held_out, predictor.noise_levels(), diagnosis.floor_seed,
                            diagnosis.floor_repeats, diagnosis.floor_noise_pieces);
  const double mean_floor = (floor[0] + floor[1] + floor[2]) / 3.0;
  std::printf("seed %llu: true model's held-out NRMSE %.5f, floor %.5f (ratio %.3f)\n",
              static_cast<unsigned long long>(seed), achieved, mean_floor, mean_floor / achieved);
  return {achieved, mean_floor};
}

// MODEL.md's transducers: pressure noise 5 kPa on a 5 kPa LSB, position noise 5 um on a 10 um
// resolution; the quantisation adds LSB^2 / 12 to the variance. The estimate must find them
// on a capture whose plant moves (third differences of the motion are small but not zero).
TEST(NoiseFloor, ReadsTheTransducerNoiseOffTheCapture) {
  const auto seed = test::model_test_seed("NoiseFloor/transducers");
  const MeasuredRecord record =
      measured_record(simulate_case(draw_case(seed, "none", short_case())));
  const SegmentPredictor predictor(record);
  const NoiseLevels n = predictor.noise_levels();
  std::printf("noise x %.3g m, p1 %.4g Pa, p2 %.4g Pa\n", n.x, n.p1, n.p2);
  const double p_expected = std::sqrt(5e3 * 5e3 + 5e3 * 5e3 / 12.0);
  const double x_expected = std::sqrt(5e-6 * 5e-6 + 1e-5 * 1e-5 / 12.0);
  EXPECT_NEAR(n.p1, p_expected, 0.2 * p_expected);
  EXPECT_NEAR(n.p2, p_expected, 0.2 * p_expected);
  EXPECT_NEAR(n.x, x_expected, 0.3 * x_expected);
}

// The floor must be what a correct model scores: the generator's own model on the held-out
// segments of clean and faulty captures, against the floor estimated with that model. One
// held-out NRMSE is itself a noisy number (a few segments mispredicted even by the true
// model, docs/model-check.md), hence the band.
TEST(NoiseFloor, IsWhatTheTrueModelScores) {
  for (const char* effect : {"none", "internal_leakage", "spool_lag"}) {
    const auto seed = test::model_test_seed(effect);
    const SyntheticCase c = draw_case(seed, effect, short_case());
    const MeasuredRecord record = measured_record(simulate_case(c));
    const SegmentPredictor predictor(record);
    const auto plan = split_record(record);
    const ModelParameters truth = true_model(c);
    const double achieved = predictor.nrmse(truth, plan.held_out);
    const auto floor = predictor.noise_floor(truth, plan.held_out, predictor.noise_levels(), seed);
    const double mean_floor = (floor[0] + floor[1] + floor[2]) / 3.0;
    std::printf("%s: true model's held-out NRMSE %.5f, floor %.5f (x %.5f p1 %.5f p2 %.5f)\n",
                effect, achieved, mean_floor, floor[0], floor[1], floor[2]);
    EXPECT_GT(mean_floor, 0.6 * achieved) << effect;
    EXPECT_LT(mean_floor, 1.4 * achieved) << effect;
  }
}

// The same on rigs whose pressures follow the spool flow noise up to hundreds of hertz: a light
// piston on a large valve, the hydraulic mode far above the sampling's Nyquist frequency
// (seed 761025 of the issue-24 evaluation: 81 mm bore, 2.4 kg, Kv 2.85e-6, 1.25 ms spool).
// MODEL.md's noise is a continuous Ornstein-Uhlenbeck process; drawn at 0.5 ms (4 pieces per
// sample) its share above 1 kHz was missing and the floor came out at 0.68 of what the true
// model scores, so a healthy capture read as `unexplained`. The diagnosis's own setting must
// come within a few per cent on such a rig and on the paper's.
TEST(NoiseFloor, FollowsTheContinuousFlowNoiseOnAStiffLightRig) {
  CaseSettings other = short_case();
  other.duration_s = 60.0;
  other.other_rig = true;
  for (const auto& [seed, settings] :
       {std::pair{std::uint64_t{761025}, other}, std::pair{std::uint64_t{771003}, short_case()}}) {
    const auto [achieved, mean_floor] = true_model_and_floor(seed, settings);
    EXPECT_GT(mean_floor, 0.85 * achieved) << "seed " << seed;
    EXPECT_LT(mean_floor, 1.2 * achieved) << "seed " << seed;
  }
}

// A rig hunting at its hydraulic mode (seed 812000 of `model evaluate --rigs other --classes
// clean`: 97 mm bore, 211 kg, Kv 3.1e-6): the closed loop keeps the ~100 Hz mode ringing by
// MPa, 5 samples a period, where no velocity read off +-6 samples of x follows it. Every
// segment of the true model then starts off the true velocity and scores 0.45 in p; the floor
// drew the start's velocity as the estimate's noise alone and came out at 0.135 (`unexplained`
// on a healthy rig). Its truth now runs in from 6 samples before the start and the guess starts
// from the velocity read off those drawn readings, as the prediction's is off the capture.
TEST(NoiseFloor, IncludesTheStartVelocitysErrorOnARigHuntingAtItsMode) {
  CaseSettings other = short_case();
  other.duration_s = 180.0;
  other.other_rig = true;
  const auto [achieved, mean_floor] = true_model_and_floor(812000, other);
  EXPECT_GT(achieved, 0.2);  // the rig hunts: far above what the transducers' noise leaves
  EXPECT_GT(mean_floor, 0.8 * achieved);
  EXPECT_LT(mean_floor, 1.25 * achieved);
}

// The piston velocity the segment starts and the force balance read off x: exact on a cubic
// (a Savitzky-Golay cubic over +-6 samples), within 1 % of the true velocity at a heavy rig's
// 17 Hz mode sampled at 500 Hz (the +-3-sample line it replaced read it 5.4 % low, and the mass
// the force balance fitted followed 3.4 % high), and as noisy as that line (0.189 / dt of the
// position noise, within 0.2 %).
TEST(PistonVelocity, ExactOnACubicAndTrueAtAHeavyRigsMode) {
  const double dt = 0.002;
  std::vector<double> cubic, mode;
  for (int k = 0; k < 40; ++k) {
    const double t = k * dt;
    cubic.push_back(0.1 - 0.3 * t + 2.0 * t * t - 40.0 * t * t * t);
    mode.push_back(0.01 * std::sin(2.0 * M_PI * 17.0 * t + 0.3));
  }
  double line_error = 0.0, cubic_error = 0.0;
  for (std::size_t k = 6; k + 6 < cubic.size(); ++k) {
    const double t = static_cast<double>(k) * dt;
    EXPECT_NEAR(PistonVelocity::at(cubic, k, dt), -0.3 + 4.0 * t - 120.0 * t * t, 1e-9) << k;
    const double w = 2.0 * M_PI * 17.0;
    const double truth = 0.01 * w * std::cos(w * t + 0.3);
    if (std::abs(truth) < 0.5 * 0.01 * w) continue;  // relative errors near a zero crossing
    double slope = 0.0;
    for (int i = -3; i <= 3; ++i)
      slope += i * mode[static_cast<std::size_t>(static_cast<int>(k) + i)];
    line_error = std::max(line_error, std::abs(slope / (28.0 * dt) / truth - 1.0));
    cubic_error = std::max(cubic_error, std::abs(PistonVelocity::at(mode, k, dt) / truth - 1.0));
  }
  std::printf("17 Hz at 500 Hz: line +-3 error %.4f, cubic +-6 error %.5f\n", line_error,
              cubic_error);
  EXPECT_GT(line_error, 0.04);  // the effect the cubic removes is there
  EXPECT_LT(cubic_error, 0.01);
  EXPECT_NEAR(PistonVelocity::noise_gain(), 1.0 / std::sqrt(28.0), 0.002 / std::sqrt(28.0));
}

// A misfit is located where it was put: a wrong Kv on clean data shows in the pressures or
// the position, and its rate follows a regressor; a leak the model lacks follows the load
// pressure (MODEL.md's signature) more than time.
// Three fresh captures (seeds first .. first + 2; LEAKMON_TEST_SEED=first reproduces the run):
// the residual's rate follows the leak term only as far as the open-loop dynamics let it (a
// pressure error moves the piston, which moves the pressures again), and in about one capture
// in 30 the load pressure was not among the two leading regressors (seed 18301707822665037876:
// velocity_sign +0.23, dp_dt -0.13, load_pressure -0.05 in p2). So per run: the misfit never in
// x and time never leading, and the load pressure among the two leading in two of three.
TEST(Misfit, FollowsTheLoadPressureForAMissingLeak) {
  const auto first = test::model_test_seed("Misfit/leak (first of 3)");
  int leading = 0;
  for (std::uint64_t k = 0; k < 3; ++k) {
    const std::uint64_t seed = first + k;
    CaseSettings s = short_case();
    const SyntheticCase c = draw_case(seed, "internal_leakage", s);
    const MeasuredRecord record = measured_record(simulate_case(c));
    const SegmentPredictor predictor(record);
    const auto plan = split_record(record);
    ModelParameters without_leak = true_model(c);
    without_leak.effects.C_L = 0.0;
    const auto floor =
        predictor.noise_floor(true_model(c), plan.held_out, predictor.noise_levels(), seed);
    const Misfit m = locate_misfit(predictor, without_leak, plan.held_out, floor);
    std::printf("seed %llu: %s\n", static_cast<unsigned long long>(seed), describe(m).c_str());
    ASSERT_GE(m.regressors.size(), 2u);
    EXPECT_NE(m.channel, "x") << "seed " << seed;
    EXPECT_NE(m.regressors[0].regressor, "time") << "seed " << seed;
    // The pressure's rate error is -C_L (p1 - p2) / C_h in p1: the load pressure or its close
    // companion, the valve opening that sets it, leads.
    leading += m.regressors[0].regressor == "load_pressure" ||
               m.regressors[1].regressor == "load_pressure";
  }
  EXPECT_GE(leading, 2) << "load pressure among the two leading regressors, of 3";
}

TEST(Calibration, FlagsValuesOnTheirBounds) {
  Calibration c;  // the rig table's nominal values: inside every bound
  EXPECT_TRUE(calibration_at_bound(c).empty());
  c.beta = 1e12;  // far above; the fit clamps to the bound, which this reports
  c.b = 0.0;
  const auto flagged = calibration_at_bound(c);
  ASSERT_EQ(flagged.size(), 2u);
  EXPECT_EQ(flagged[0], "beta");
  EXPECT_EQ(flagged[1], "b");
  const Calibration inside = within_bounds(c);
  EXPECT_TRUE(calibration_at_bound(inside).empty());
  EXPECT_LT(inside.beta, 1e12);
}

TEST(EffectLibrary, JointCandidateAppliesEachPartToItsOwnParameters) {
  const auto library = effect_library(0.0, true);
  const EffectCandidate* leak = nullptr;
  const EffectCandidate* lag = nullptr;
  const EffectCandidate* oil = nullptr;
  for (const auto& c : library) {
    if (c.effect == "internal_leakage") leak = &c;
    if (c.effect == "sensor_lag" && c.variant == "p2") lag = &c;
    if (c.effect == "oil_temperature") oil = &c;
  }
  ASSERT_TRUE(leak && lag && oil);
  const EffectCandidate joint = combine({*leak, *lag, *oil});
  EXPECT_EQ(joint.effect, "internal_leakage+sensor_lag+oil_temperature");
  ASSERT_EQ(joint.parameters.size(), 3u);
  EffectParameters e;
  joint.apply(e, {2e-12, 0.005, 0.046});
  EXPECT_DOUBLE_EQ(e.C_L, 2e-12);
  EXPECT_DOUBLE_EQ(e.tau_s, 0.005);
  EXPECT_EQ(e.lag_channel, PressureChannel::p2);
  EXPECT_DOUBLE_EQ(e.visc_slope, 0.046);
  EXPECT_TRUE(joint.plausible({2e-12, 0.005, 0.046}));
  EXPECT_FALSE(joint.plausible({-1e-12, 0.005, 0.046}));  // a negative leak is no leak
  EXPECT_FALSE(effect_library(0.0, false).back().effect == "oil_temperature");
}

// A transducer lag shorter than half the sample period is a sub-sample delay of the readings,
// not a resolvable lag (effect_library.hpp): at 500 Hz the 0.72 ms lag that was named as a
// third cause next to Coulomb friction and a valve bias is no instance of sensor_lag, alone or
// in a joint candidate, while MODEL.md's range (2-10 ms) and the evaluation's `beyond` lags
// (1.33 ms) stay plausible. The smallest-instance rule alone (a fifth of 2 ms) let it through.
TEST(EffectLibrary, LagShorterThanHalfASamplePeriodIsNoSensorLag) {
  const auto find = [](const std::vector<EffectCandidate>& library, const std::string& effect,
                       const std::string& variant) {
    for (const auto& c : library) {
      if (c.effect == effect && c.variant == variant) return c;
    }
    ADD_FAILURE() << effect << " " << variant << " missing";
    return EffectCandidate{};
  };
  const auto at_500_hz = effect_library(0.0, false, 0.002);
  for (const char* channel : {"p1", "p2"}) {
    const EffectCandidate lag = find(at_500_hz, "sensor_lag", channel);
    EXPECT_DOUBLE_EQ(lag.smallest(), 0.001) << channel;
    EXPECT_FALSE(lag.plausible({0.00072})) << channel;
    EXPECT_FALSE(lag.plausible({0.00099})) << channel;
    EXPECT_TRUE(lag.plausible({0.0010 + 1e-6})) << channel;
    EXPECT_TRUE(lag.plausible({0.002 / 1.5})) << channel;
    EXPECT_TRUE(lag.plausible({0.002})) << channel;
    EXPECT_TRUE(lag.plausible({0.01})) << channel;
  }
  const EffectCandidate friction = find(at_500_hz, "coulomb_friction", "");
  const EffectCandidate bias = find(at_500_hz, "valve_bias", "");
  const EffectCandidate lag = find(at_500_hz, "sensor_lag", "p1");
  const EffectCandidate triple = combine({friction, bias, lag});
  EXPECT_FALSE(triple.plausible({250.0, 0.2, 0.00072}));
  EXPECT_TRUE(triple.plausible({250.0, 0.2, 0.003}));
  // Sampled at 2 kHz the same lag spans more than a period and is resolvable again; other
  // effects do not depend on the sample period.
  const auto at_2_khz = effect_library(0.0, false, 0.0005);
  EXPECT_TRUE(find(at_2_khz, "sensor_lag", "p1").plausible({0.00072}));
  EXPECT_DOUBLE_EQ(find(at_2_khz, "sensor_lag", "p1").smallest(), 0.002 / 5.0);
  EXPECT_DOUBLE_EQ(friction.smallest(), find(at_2_khz, "coulomb_friction", "").smallest());
  // Without a sample period the rule is the smallest-instance rule alone.
  EXPECT_TRUE(find(effect_library(0.0, false), "sensor_lag", "p1").plausible({0.00072}));
}

}  // namespace
}  // namespace leakmon::model
