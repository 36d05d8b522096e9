// Drifting operating conditions (MODEL.md): Walther's equation against MODEL.md's oil table,
// the rig at 40 degC bit-identical to the stationary one, a warm-up raising the valve's null
// leakage as the viscosity ratio predicts, supply set-point changes followed at rest, the
// external leak's onset, and the allocation-free step with every condition active.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sim/oil.hpp"
#include "sim/plant.hpp"
#include "sim/rig.hpp"
#include "sim/simulate.hpp"
#include "sim/valve.hpp"
#include "tests/sim/sim_test_support.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::sim {
namespace {

TEST(OilViscosity, WaltherReproducesTheDataSheetAndModelTable) {
  struct Row {
    int grade;
    double nu40, nu100, slope;
  };
  // MODEL.md "Drifting operating conditions": -d ln(nu)/dT at 40 degC.
  for (const Row row :
       {Row{32, 32.0, 5.4, 0.043}, Row{46, 46.0, 6.8, 0.046}, Row{68, 68.0, 8.7, 0.050}}) {
    const Oil oil = *Oil::iso_vg(row.grade);
    EXPECT_NEAR(oil.nu(40.0), row.nu40, 1e-9 * row.nu40) << row.grade;
    EXPECT_NEAR(oil.nu(100.0), row.nu100, 1e-9 * row.nu100) << row.grade;
    EXPECT_NEAR(oil.viscosity_slope(40.0), row.slope, 0.002) << row.grade;
    // The analytic slope agrees with a finite difference of nu(T).
    const double fd = -(std::log(oil.nu(40.01)) - std::log(oil.nu(39.99))) / 0.02;
    EXPECT_NEAR(oil.viscosity_slope(40.0), fd, 1e-6) << row.grade;
    EXPECT_EQ(oil.ratio(40.0), 1.0);
    EXPECT_GT(oil.ratio(60.0), 2.0);  // 20 K warmer: "a factor 2-3"
    EXPECT_LT(oil.ratio(60.0), 3.0);
    EXPECT_LT(oil.ratio(20.0), 0.5);
  }
  EXPECT_FALSE(Oil::iso_vg(100).has_value());
  EXPECT_EQ(Oil::standard().name(), "ISO VG 46");
  EXPECT_THROW(Oil(5.0, 6.0), std::invalid_argument);
}

TEST(OilViscosity, OneKelvinRaisesTheNullLeakageByAboutFivePercent) {
  const Oil oil = Oil::standard();
  EXPECT_NEAR(oil.ratio(41.0), 1.047, 0.005);
  EXPECT_NEAR(bulk_modulus_factor(50.0), 0.97, 1e-12);
  EXPECT_NEAR(friction_factor(2.0), 0.75, 1e-12);
}

Scenario every_effect(double duration_s) {
  Scenario s = preset("paper-fig10", 9);
  s.duration_s = duration_s;
  s.effects.internal_leakage->onset_s = 1.0;
  for (const auto name : Effects::names()) {
    if (name != "internal_leakage") s.effects.enable(name);
  }
  return s;
}

void expect_identical(const capture::Capture& a, const capture::Capture& b) {
  ASSERT_EQ(a.columns, b.columns);
  ASSERT_EQ(a.rows(), b.rows());
  for (std::size_t c = 0; c < a.columns.size(); ++c) {
    for (std::size_t k = 0; k < a.rows(); ++k) {
      ASSERT_EQ(a.values[c][k], b.values[c][k]) << a.columns[c] << " row " << k;
    }
  }
}

TEST(Conditions, AtFortyDegreesEveryTrajectoryIsBitIdentical) {
  for (Scenario s : {preset("paper-fig10", 3), every_effect(3.0)}) {
    const capture::Capture stationary = simulate(s);
    s.conditions.temperature = TemperatureProfile{};  // constant 40 degC
    s.conditions.supply = {{0.5, s.params.ps, 0.0}};  // a "change" to the same set-point
    ASSERT_TRUE(s.conditions.any());
    expect_identical(stationary, simulate(s));
    // Another oil at 40 degC: r(40) = 1 for every oil.
    s.conditions.oil = *Oil::iso_vg(68);
    expect_identical(stationary, simulate(s));
  }
}

// Valve opening that holds chamber 1 at rest against the null leakage, divided by what the
// nominal C_n needs: the viscosity ratio the plant runs at. At rest q1 = 0:
// Kv o sg(.) + r C_n ((ps - p1) - (p1 - pt)) = 0 (MODEL.md "valve", "null leak").
double measured_null_leak_ratio(const std::vector<RigSample>& run, const Parameters& p) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t k = run.size() - 250; k < run.size(); ++k) {
    const RigSample& s = run[k];
    const double o = s.xs_true;
    const double orifice_flow = o >= 0.0 ? p.Kv * o * orifice(s.ps_true - s.p1_true, p.dp_lin)
                                         : p.Kv * o * orifice(s.p1_true - p.pt, p.dp_lin);
    sum += -orifice_flow / (p.C_n * ((s.ps_true - s.p1_true) - (s.p1_true - p.pt)));
    ++n;
  }
  return sum / n;
}

TEST(Conditions, WarmUpRaisesTheNullLeakageAsTheViscosityRatioPredicts) {
  // Fault-tolerant loop (integral action) holding 5 cm against the spring: at rest the spool
  // opening exactly cancels the null leakage, so it measures r C_n.
  const Oil oil = Oil::standard();
  for (const double T : {25.0, 40.0, 55.0}) {
    Scenario s = testing::held_level(0.05, 12.0, ControllerKind::fault_tolerant);
    s.conditions.temperature = TemperatureProfile{};
    s.conditions.temperature->T_work = T;
    const auto run = testing::run(s);
    EXPECT_NEAR(measured_null_leak_ratio(run, s.params), oil.ratio(T), 0.01 * oil.ratio(T))
        << "T = " << T;
    // At rest the load is the spring's whatever the temperature: A (p1 - p2) = K_s x.
    const double load = s.params.A() * (run.back().p1_true - run.back().p2_true);
    EXPECT_NEAR(load, s.params.K_s * run.back().x_true, 1e-3 * std::abs(load));
  }
  // A warm-up 20 -> 50 degC (tau 8 s): early the opening follows r(T(t)) of the cold oil, at
  // the end that of the warm oil, a factor > 4 apart.
  Scenario s = testing::held_level(0.05, 60.0, ControllerKind::fault_tolerant);
  TemperatureProfile warm;
  warm.kind = TemperatureProfile::Kind::warm_up;
  warm.T0 = 20.0;
  warm.T_work = 50.0;
  warm.tau_s = 8.0;
  warm.start_s = 6.0;
  s.conditions.temperature = warm;
  const auto run = testing::run(s);
  const std::vector<RigSample> cold(run.begin(), run.begin() + 3000);  // t < 6 s: still 20 degC
  const double r_cold = measured_null_leak_ratio(cold, s.params);
  const double r_warm = measured_null_leak_ratio(run, s.params);
  EXPECT_NEAR(r_cold, oil.ratio(20.0), 0.01 * oil.ratio(20.0));
  EXPECT_NEAR(r_warm, oil.ratio(warm.at(60.0)), 0.01 * oil.ratio(50.0));
  EXPECT_GT(r_warm / r_cold, 4.0);
  EXPECT_NEAR(run.back().temp_true, warm.at(59.998), 1e-9);
}

TEST(Conditions, LeakSizeIsStatedAtFortyDegrees) {
  // q_int = r(T) C_L (p1 - p2): the same needle valve passes 1.86 times the flow at 55 degC.
  Scenario s = testing::held_level(0.04, 3.0, ControllerKind::basic);
  s.effects.internal_leakage = InternalLeakage{2e-12, 1.0, 0.0};
  s.conditions.temperature = TemperatureProfile{};
  s.conditions.temperature->T_work = 55.0;
  const double r = Oil::standard().ratio(55.0);
  EXPECT_NEAR(r, 1.86, 0.01);
  const auto run = testing::run(s);
  for (const RigSample& sample : run) {
    const double expected = sample.t < 1.0 ? 0.0 : r * 2e-12 * (sample.p1_true - sample.p2_true);
    ASSERT_NEAR(sample.q_int, expected, 1e-12 * std::abs(expected) + 1e-24) << sample.t;
  }
  EXPECT_GT(std::abs(run.back().q_int), 1e-6);
}

TEST(Conditions, ChamberPressuresFollowASupplyStepAtRest) {
  Scenario s = testing::held_level(0.03, 16.0, ControllerKind::basic);
  s.conditions.supply = {{6.0, 14e6, 2.0}, {12.0, 16e6, 0.0}};
  const auto run = testing::run(s);
  const auto sum = [](const RigSample& r) { return r.p1_true + r.p2_true; };
  const auto supply = [](const RigSample& r) { return r.ps_true; };
  EXPECT_NEAR(testing::mean_over(run, 5.0, 6.0, supply), 17.2e6, 1.0);
  EXPECT_NEAR(testing::mean_over(run, 10.0, 12.0, supply), 14e6, 1.0);
  EXPECT_NEAR(testing::mean_over(run, 15.0, 16.0, supply), 16e6, 1.0);
  // Mid-ramp the set-point is half-way.
  EXPECT_NEAR(run[3500].ps_true, 15.6e6, 1e-6 * 15.6e6);
  // At rest p1 + p2 = ps + pt (MODEL.md), before and after each change.
  EXPECT_NEAR(testing::mean_over(run, 5.0, 6.0, sum), 17.3e6, 0.01 * 17.3e6);
  EXPECT_NEAR(testing::mean_over(run, 10.0, 12.0, sum), 14.1e6, 0.01 * 14.1e6);
  EXPECT_NEAR(testing::mean_over(run, 15.0, 16.0, sum), 16.1e6, 0.01 * 16.1e6);
}

TEST(Conditions, ExternalLeakOpensAtItsOnset) {
  for (const int chamber : {1, 2}) {
    Scenario s = testing::held_level(0.03, 8.0, ControllerKind::basic);
    s.effects.external_leakage = ExternalLeakage{1e-12, chamber, 4.0, 0.0};
    const auto run = testing::run(s);
    Scenario healthy = s;
    healthy.effects.external_leakage.reset();
    const auto reference = testing::run(healthy);
    const auto sum = [](const RigSample& r) { return r.p1_true + r.p2_true; };
    for (std::size_t k = 0; k < 2000; ++k) ASSERT_EQ(run[k].p1_true, reference[k].p1_true);
    // After the onset p1 + p2 falls (one chamber drains to tank).
    EXPECT_LT(testing::mean_over(run, 7.0, 8.0, sum),
              testing::mean_over(reference, 7.0, 8.0, sum) - 1e5)
        << chamber;
  }
}

TEST(Conditions, StepStaysAllocationFreeWithDriftingConditions) {
  Scenario s = every_effect(4.0);
  TemperatureProfile t;
  t.kind = TemperatureProfile::Kind::warm_up_cooler;
  t.tau_s = 2.0;
  t.cooler_start_s = 1.0;
  t.period_s = 1.0;
  s.conditions.temperature = t;
  s.conditions.supply = {{1.0, 14e6, 0.5}, {3.0, 18e6, 0.0}};
  s.effects.external_leakage->onset_s = 2.0;
  s.record.ps = s.record.temp = true;
  SensorFault spikes{SensorFault::Kind::spikes, SensorChannel::ps, 0.5, 3.0};
  spikes.rate_per_min = 600.0;
  SensorFault gap{SensorFault::Kind::dropout, SensorChannel::x, 1.0, 1.0};
  gap.gap = true;
  s.faults = {SensorFault{SensorFault::Kind::frozen, SensorChannel::p1, 1.0, 2.0}, spikes, gap,
              SensorFault{SensorFault::Kind::saturated, SensorChannel::temp, 2.0, 1.0}};
  Rig rig(s);
  double checksum = 0.0;
  {
    test::AllocationScope scope;
    for (std::uint64_t k = 0; k < s.samples(); ++k) checksum += rig.step().p1;
    rig.reset();
    for (std::uint64_t k = 0; k < 500; ++k) checksum += rig.step().ps;
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_TRUE(std::isfinite(checksum));
}

// The automatic step is sized for the coldest oil of the profile: halving it moves the
// trajectories by less than 5 % of a sensor LSB through a warm-up from 10 degC with supply
// changes, as on the stationary presets (numerics_test).
TEST(Conditions, StepHalvingHoldsThroughAColdWarmUpAndSupplyChanges) {
  Scenario s = preset("paper-fig10", 8);
  s.duration_s = 20.0;
  s.sensors.enabled = false;
  TemperatureProfile cold;
  cold.kind = TemperatureProfile::Kind::warm_up_cooler;
  cold.T0 = 10.0;
  cold.T_work = 55.0;
  cold.tau_s = 6.0;
  cold.period_s = 3.0;
  cold.amplitude = 3.0;
  cold.cooler_start_s = 12.0;
  s.conditions.temperature = cold;
  s.conditions.supply = {{5.0, 13e6, 1.0}, {14.0, 19e6, 0.0}};
  Scenario coarse = s, fine = s;
  coarse.integration_step_s = integration_step(s);
  fine.integration_step_s = coarse.integration_step_s / 2.0;
  const auto a = testing::run(coarse);
  const auto b = testing::run(fine);
  double dp = 0.0, dx = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (std::getenv("DIAG") && std::abs(a[k].p1_true - b[k].p1_true) > 100)
      std::printf("t %g d %g\n", a[k].t, a[k].p1_true - b[k].p1_true);
    dp = std::max(
        {dp, std::abs(a[k].p1_true - b[k].p1_true), std::abs(a[k].p2_true - b[k].p2_true)});
    dx = std::max(dx, std::abs(a[k].x_true - b[k].x_true));
  }
  std::printf("step %g s: halving moves p by %.1f Pa, x by %.3g m\n", coarse.integration_step_s, dp,
              dx);
  EXPECT_LT(dp, 0.05 * s.sensors.pressure_lsb());
  EXPECT_LT(dx, 0.05 * s.sensors.position_resolution);
}

TEST(TemperatureProfiles, FollowTheirDefinitions) {
  TemperatureProfile p;
  p.kind = TemperatureProfile::Kind::warm_up;
  p.T0 = 20.0;
  p.T_work = 50.0;
  p.tau_s = 600.0;
  p.start_s = 60.0;
  EXPECT_EQ(p.at(30.0), 20.0);
  EXPECT_NEAR(p.at(660.0), 50.0 - 30.0 * std::exp(-1.0), 1e-12);
  p.kind = TemperatureProfile::Kind::cooler;
  p.amplitude = 3.0;
  p.period_s = 400.0;
  p.cooler_start_s = 0.0;
  EXPECT_NEAR(p.at(100.0), 53.0, 1e-12);
  EXPECT_NEAR(p.at(300.0), 47.0, 1e-12);
  p.kind = TemperatureProfile::Kind::warm_up_cooler;
  p.cooler_start_s = 1860.0;
  EXPECT_NEAR(p.at(1000.0), 50.0 - 30.0 * std::exp(-940.0 / 600.0), 1e-12);
  EXPECT_NEAR(p.at(1960.0), 50.0 - 30.0 * std::exp(-1900.0 / 600.0) + 3.0, 1e-12);
  EXPECT_EQ(p.minimum(), 17.0);
}

}  // namespace
}  // namespace leakmon::sim
