// One test per effect of MODEL.md's library: each changes the trajectory the way the last
// paragraph of MODEL.md says it shows in residuals, measured against the nominal model run on
// the same seed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "sim/chamber.hpp"
#include "sim/plant.hpp"
#include "sim/rig.hpp"
#include "tests/sim/sim_test_support.hpp"

namespace leakmon::sim {
namespace {

using testing::mean_over;
using testing::run;

Parameters quiet() {
  Parameters p;
  p.sigma_w = 0.0;
  return p;
}

// Resting under the spring with the fault-tolerant loop (integral action), noise-free.
std::vector<RigSample> rest_under_load(const Effects& effects) {
  Scenario s = testing::held_level(0.05, 8.0, ControllerKind::fault_tolerant, 6);
  s.effects = effects;
  return run(s);
}

double late_mean(const std::vector<RigSample>& r, double (*field)(const RigSample&)) {
  return mean_over(r, 6.0, 8.0, field);
}

double sum_pressure(const RigSample& r) { return r.p1_true + r.p2_true; }
double load_pressure(const RigSample& r) { return r.p1_true - r.p2_true; }
double command(const RigSample& r) { return r.u; }

// Amplitude of a sinusoid at f in x (sampled at fs): one DFT bin with a Hann window, so the
// low-frequency power of the reference steps does not leak into it.
double line_amplitude(const std::vector<double>& x, double f, double fs) {
  std::complex<double> acc = 0.0;
  double weights = 0.0;
  const double n = static_cast<double>(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double w = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * k / n);
    acc += w * x[k] * std::exp(std::complex<double>(0.0, -2.0 * std::numbers::pi * f * k / fs));
    weights += w;
  }
  return 2.0 * std::abs(acc) / weights;
}

// Median line amplitude over 20 frequencies within +-10 Hz of f (excluding +-1 Hz): the
// broadband floor around f.
double floor_near(const std::vector<double>& x, double f, double fs) {
  std::vector<double> amplitudes;
  for (int i = 1; i <= 10; ++i) {
    amplitudes.push_back(line_amplitude(x, f + 0.97 * i + 0.3, fs));
    amplitudes.push_back(line_amplitude(x, f - 0.97 * i - 0.3, fs));
  }
  std::nth_element(amplitudes.begin(), amplitudes.begin() + 10, amplitudes.end());
  return amplitudes[10];
}

// p1 + p2: the supply feeds both chambers in phase, while the hydraulic mode moves them in
// opposition, so a supply-borne line stands out in the sum.
std::vector<double> sum_pressures(const std::vector<RigSample>& samples) {
  std::vector<double> out;
  for (const auto& r : samples) out.push_back(r.p1 + r.p2);
  return out;
}

TEST(InternalLeakage, FlowsInProportionToLoadPressureAtRestWithSumPressureUnchanged) {
  Effects leak;
  leak.internal_leakage = InternalLeakage{3e-12, 2.0, 0.0};
  const auto healthy = rest_under_load({});
  const auto leaking = rest_under_load(leak);
  for (const auto& r : leaking) {
    const double expected = r.t < 2.0 ? 0.0 : 3e-12 * (r.p1_true - r.p2_true);
    ASSERT_NEAR(r.q_int, expected, 1e-9 * std::abs(expected) + 1e-20) << r.t;
  }
  const double load = late_mean(leaking, load_pressure);
  EXPECT_GT(std::abs(load), 5e6);  // the spring's load: about 6.3 MPa at 5 cm
  EXPECT_NEAR(late_mean(leaking, load_pressure), late_mean(healthy, load_pressure),
              0.01 * std::abs(load));
  EXPECT_NEAR(late_mean(leaking, sum_pressure), late_mean(healthy, sum_pressure), 0.15e6);
  EXPECT_GT(std::abs(mean_over(leaking, 6.0, 8.0, [](const RigSample& r) { return r.q_int; })),
            1.5e-5);
}

TEST(ExternalLeakage, ShiftsTheSumPressureAndNotTheLoadPressure) {
  for (const int chamber : {1, 2}) {
    Effects ext;
    ext.external_leakage = ExternalLeakage{1e-12, chamber};
    const auto healthy = rest_under_load({});
    const auto leaking = rest_under_load(ext);
    const double sum_shift = late_mean(leaking, sum_pressure) - late_mean(healthy, sum_pressure);
    const double load_shift = late_mean(leaking, load_pressure) - late_mean(healthy, load_pressure);
    EXPECT_LT(sum_shift, -0.5e6) << "chamber " << chamber;
    EXPECT_LT(std::abs(load_shift), 0.05 * std::abs(sum_shift)) << "chamber " << chamber;
  }
}

// Residual force A (p1 - p2) - K_s x - b v - m a on an open-loop sinusoidal motion: the
// nominal model leaves none; Coulomb friction leaves +-F_C that flips with the velocity.
TEST(CoulombFriction, JumpsByTwiceFcAtEveryVelocityReversal) {
  for (const double F_C : {0.0, 250.0}) {
    const Parameters p = quiet();
    Effects effects;
    if (F_C > 0.0) effects.coulomb_friction = CoulombFriction{F_C};
    Plant plant(p, effects, 1, 5e-5);
    std::vector<PlantState> states;
    const double dt = 0.002;
    for (int k = 0; k < 2000; ++k) {
      plant.advance(1.5 * std::sin(2.0 * std::numbers::pi * 1.5 * k * dt), k * dt, dt);
      states.push_back(plant.state());
    }
    double moving_up = 0.0, moving_down = 0.0;
    int n_up = 0, n_down = 0;
    for (std::size_t k = 500; k + 1 < states.size(); ++k) {
      const PlantState& s = states[k];
      const double a = (states[k + 1].v - states[k - 1].v) / (2.0 * dt);
      const double residual = p.A() * (s.p1 - s.p2) - p.K_s * s.x - p.b * s.v - p.m * a;
      if (s.v > 0.01) {
        moving_up += residual;
        ++n_up;
      } else if (s.v < -0.01) {
        moving_down += residual;
        ++n_down;
      }
    }
    ASSERT_GT(n_up, 100);
    ASSERT_GT(n_down, 100);
    const double jump = moving_up / n_up - moving_down / n_down;
    EXPECT_NEAR(jump, 2.0 * F_C, 0.1 * 2.0 * 250.0) << "F_C " << F_C;
  }
}

// From the same instant with the same flows, the pressure rate scales by beta_e(p)/beta:
// most slowed in the low-pressure chamber.
TEST(EntrainedAir, SlowsPressureTransientsMostInTheLowPressureChamber) {
  PlantState start;
  start.xs = 0.5;
  start.p1 = 1.0e6;
  start.p2 = 15.0e6;
  const double dt = 1e-5;
  const auto pressure_change = [&](const Effects& effects) {
    Plant plant(quiet(), effects, 1, dt);
    plant.set_state(start);
    plant.advance(5.0, 0.0, dt);
    return std::pair{plant.state().p1 - start.p1, plant.state().p2 - start.p2};
  };
  Effects air;
  air.entrained_air = EntrainedAir{0.1};
  const auto [nominal1, nominal2] = pressure_change({});
  const auto [aerated1, aerated2] = pressure_change(air);
  const double beta = Parameters::nominal().beta;
  EXPECT_NEAR(aerated1 / nominal1, entrained_air_bulk_modulus(beta, 0.1, 1.0e6) / beta, 0.02);
  EXPECT_NEAR(aerated2 / nominal2, entrained_air_bulk_modulus(beta, 0.1, 15.0e6) / beta, 0.02);
  EXPECT_LT(aerated1 / nominal1, 0.6);
  EXPECT_LT(aerated1 / nominal1, aerated2 / nominal2 - 0.2);
}

TEST(ValveOverlap, SwallowsSmallCommandsAndBarelyChangesLargeOnes) {
  const auto travel = [](double u, double seconds, const Effects& effects) {
    Plant plant(quiet(), effects, 1, 2.5e-4);
    for (int k = 0; k * 0.002 < seconds; ++k) plant.advance(u, k * 0.002, 0.002);
    return plant.state().x;
  };
  Effects overlap;
  overlap.valve_overlap = ValveOverlap{0.02};
  // 0.1 V opens the spool 1 %: inside the 2 % dead band.
  const double small_nominal = travel(0.1, 0.5, {});
  const double small_overlap = travel(0.1, 0.5, overlap);
  EXPECT_GT(small_nominal, 2e-3);
  EXPECT_LT(std::abs(small_overlap), 0.01 * small_nominal);
  // 2 V opens it 20 %: the dead band takes a tenth off the opening, not rescaled.
  const double large_ratio = travel(2.0, 0.05, overlap) / travel(2.0, 0.05, {});
  EXPECT_GT(large_ratio, 0.8);
  EXPECT_LT(large_ratio, 0.97);
}

TEST(ValveBias, IsAConstantCommandOffset) {
  Effects bias;
  bias.valve_bias = ValveBias{0.2};
  const auto healthy = rest_under_load({});
  const auto biased = rest_under_load(bias);
  // The integrating loop cancels the bias: the recorded command moves by -u0.
  EXPECT_NEAR(late_mean(biased, command) - late_mean(healthy, command), -0.2, 0.01);
  // Over a whole random run the offset is the same constant.
  Scenario s = preset("healthy-ft", 8);
  s.duration_s = 30.0;
  Scenario b = s;
  b.effects.valve_bias = ValveBias{-0.15};
  const double shift =
      mean_over(run(b), 0.0, 30.0, command) - mean_over(run(s), 0.0, 30.0, command);
  EXPECT_NEAR(shift, 0.15, 0.02);
}

// A slower spool lags the command by (tau_true - tau) d(u/u_max)/dt for slow commands.
TEST(SpoolLag, DifferenceFromTheNominalSpoolFollowsTheCommandRate) {
  const double tau_true = 0.012, tau = Parameters::nominal().tau;
  Effects lag;
  lag.spool_lag = SpoolLag{tau_true};
  Plant nominal(quiet(), {}, 1, 2.5e-4), lagged(quiet(), lag, 1, 2.5e-4);
  const double omega = 2.0 * std::numbers::pi * 1.0;
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * 0.002;
    const double u = 2.0 * std::sin(omega * t);
    nominal.advance(u, t, 0.002);
    lagged.advance(u, t, 0.002);
    if (k < 500) continue;
    const double rate = 2.0 * omega * std::cos(omega * (t + 0.002)) / 10.0;  // d(u/u_max)/dt
    const double difference = lagged.state().xs - nominal.state().xs;
    sxy += rate * difference;
    sxx += rate * rate;
    syy += difference * difference;
  }
  EXPECT_NEAR(sxy / sxx, -(tau_true - tau), 0.05 * (tau_true - tau));
  EXPECT_GT(sxy / std::sqrt(sxx * syy), -1.0);
  EXPECT_LT(sxy / std::sqrt(sxx * syy), -0.99);  // the difference is the rate, scaled
}

TEST(SupplyRipple, IsASpectralLineAtItsFrequency) {
  Scenario s = preset("healthy", 9);
  s.duration_s = 30.0;
  Scenario r = s;
  r.effects.supply_ripple = SupplyRipple{5e5, 60.0};
  const auto healthy = sum_pressures(run(s));
  const auto rippled = sum_pressures(run(r));
  const double at_f = line_amplitude(rippled, 60.0, 500.0);
  EXPECT_GT(at_f, 5.0 * floor_near(rippled, 60.0, 500.0));  // 25x the power
  EXPECT_GT(at_f, 10.0 * line_amplitude(healthy, 60.0, 500.0));
}

TEST(SupplyDroop, SagsWithTheFlowDrawnAndSolvesTheAlgebraicLoop) {
  Scenario s = preset("healthy", 10);
  s.duration_s = 10.0;
  s.effects.supply_droop = SupplyDroop{2e10};
  Rig rig(s);
  double droop_moving = 0.0, droop_resting = 0.0;
  int n_moving = 0, n_resting = 0;
  const double ps0 = s.params.ps;
  for (std::uint64_t k = 0; k < s.samples(); ++k) {
    rig.step();
    const PlantFlows f = rig.plant().flows();
    ASSERT_NEAR(f.ps + 2e10 * f.q_supply, ps0, 1e-6 * ps0);
    const double speed = std::abs(rig.plant().state().v);
    if (speed > 0.05) {
      droop_moving += ps0 - f.ps;
      ++n_moving;
    } else if (speed < 0.002) {
      droop_resting += ps0 - f.ps;
      ++n_resting;
    }
  }
  ASSERT_GT(n_moving, 20);
  ASSERT_GT(n_resting, 100);
  EXPECT_GT(droop_moving / n_moving, 0.5e6);
  EXPECT_GT(droop_moving / n_moving, 5.0 * droop_resting / n_resting);
}

TEST(SensorOffset, ShiftsOneChannelOnly) {
  Scenario s = preset("healthy", 12);
  s.duration_s = 10.0;
  s.effects.sensor_offset = SensorOffset{-1.5e5, PressureChannel::p2};
  const auto samples = run(s);
  const auto mean_error = [&](bool p1) {
    return mean_over(samples, 0.0, 10.0,
                     [p1](const RigSample& r) { return p1 ? r.p1 - r.p1_true : r.p2 - r.p2_true; });
  };
  EXPECT_NEAR(mean_error(false), -1.5e5, 1e3);
  EXPECT_NEAR(mean_error(true), 0.0, 1e3);
}

// The lagging channel obeys tau_s dm/dt = p - m; the other reads the true pressure.
TEST(SensorLag, DelaysOneChannelThroughAFirstOrderLag) {
  Scenario s = preset("healthy", 13);
  s.duration_s = 10.0;
  s.sensors.enabled = false;
  s.effects.sensor_lag = SensorLag{0.006, PressureChannel::p1};
  const auto samples = run(s);
  double sxy = 0.0, sxx = 0.0, lag_error = 0.0;
  for (std::size_t k = 1; k + 1 < samples.size(); ++k) {
    const double rate = (samples[k + 1].p1 - samples[k - 1].p1) / 0.004;
    const double gap = samples[k].p1_true - samples[k].p1;
    sxy += rate * gap;
    sxx += rate * rate;
    lag_error = std::max(lag_error, std::abs(gap));
    ASSERT_EQ(samples[k].p2, samples[k].p2_true);
  }
  EXPECT_GT(lag_error, 1e5);
  EXPECT_NEAR(sxy / sxx, 0.006, 0.0006);
}

TEST(SeveralEffects, ActAtOnceEachWithItsOwnSignature) {
  Scenario s = preset("healthy", 14);
  s.duration_s = 20.0;
  s.effects.internal_leakage = InternalLeakage{2e-12, 5.0, 1.0};
  s.effects.sensor_offset = SensorOffset{1e5, PressureChannel::p1};
  s.effects.supply_ripple = SupplyRipple{4e5, 90.0};
  s.effects.coulomb_friction = CoulombFriction{100.0};
  ASSERT_EQ(s.effects.describe().size(), 4u);
  const auto samples = run(s);
  for (const auto& r : samples) {
    const double C_L = r.t < 5.0 ? 0.0 : 2e-12 * std::min(r.t - 5.0, 1.0);
    ASSERT_NEAR(r.q_int, C_L * (r.p1_true - r.p2_true), 1e-9 * std::abs(r.q_int) + 1e-20) << r.t;
  }
  EXPECT_NEAR(mean_over(samples, 0.0, 20.0, [](const RigSample& r) { return r.p1 - r.p1_true; }),
              1e5, 1e3);
  const auto sum = sum_pressures(samples);
  EXPECT_GT(line_amplitude(sum, 90.0, 500.0), 5.0 * floor_near(sum, 90.0, 500.0));
}

}  // namespace
}  // namespace leakmon::sim
