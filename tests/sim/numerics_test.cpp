// Numerics of the plant integration: the step-halving check that judges the default RK4
// step, mass balance of the chambers, the static equilibria the equations imply, and
// closed-loop stability of both controllers over random references.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/plant.hpp"
#include "sim/rig.hpp"
#include "sim/scenario.hpp"
#include "tests/sim/sim_test_support.hpp"

namespace leakmon::sim {
namespace {

struct Difference {
  double pressure = 0.0, position = 0.0;
};

Difference halving_difference(Scenario scenario) {
  Scenario fine = scenario;
  scenario.integration_step_s = integration_step(scenario);
  fine.integration_step_s = scenario.integration_step_s / 2.0;
  Rig coarse_rig(scenario), fine_rig(fine);
  Difference d;
  for (std::uint64_t k = 0; k < scenario.samples(); ++k) {
    const RigSample a = coarse_rig.step();
    const RigSample b = fine_rig.step();
    d.pressure =
        std::max({d.pressure, std::abs(a.p1_true - b.p1_true), std::abs(a.p2_true - b.p2_true)});
    d.position = std::max(d.position, std::abs(a.x_true - b.x_true));
  }
  return d;
}

class StepHalving : public ::testing::TestWithParam<std::string> {};

// The default step is chosen by this check: halving it must move pressures and position by
// less than one sensor LSB (5.05 kPa, 10 um). With ideal sensors the loop is smooth and the
// difference is pure integration error; with real sensors a quantisation level can flip, so
// that case only has to stay below one LSB.
TEST_P(StepHalving, ChangesTrajectoriesByLessThanOneSensorLsb) {
  Scenario s = preset(GetParam(), 11);
  s.duration_s = std::min(s.duration_s, 20.0);
  if (s.effects.internal_leakage) s.effects.internal_leakage->onset_s = 10.0;
  const double lsb = s.sensors.pressure_lsb();
  const double resolution = s.sensors.position_resolution;

  Scenario ideal = s;
  ideal.sensors.enabled = false;
  const Difference smooth = halving_difference(ideal);
  EXPECT_LT(smooth.pressure, 0.05 * lsb);
  EXPECT_LT(smooth.position, 0.05 * resolution);

  const Difference measured = halving_difference(s);
  EXPECT_LT(measured.pressure, lsb);
  EXPECT_LT(measured.position, resolution);
}

INSTANTIATE_TEST_SUITE_P(Presets, StepHalving,
                         ::testing::Values("healthy", "healthy-ft", "paper-fig10", "paper-fig16"),
                         [](const auto& param_info) {
                           std::string name = param_info.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// Stiffening effects shorten the automatic step; the halving check must hold there too.
TEST(StepHalvingWithEffects, HoldsWithEveryPlantEffectActive) {
  Scenario s = preset("paper-fig10", 5);
  s.duration_s = 12.0;
  s.effects.internal_leakage->onset_s = 6.0;
  s.effects.coulomb_friction = CoulombFriction{300.0};
  s.effects.entrained_air = EntrainedAir{0.1};
  s.effects.valve_overlap = ValveOverlap{0.02};
  s.effects.spool_lag = SpoolLag{0.008};
  s.effects.supply_ripple = SupplyRipple{5e5, 120.0};
  s.effects.supply_droop = SupplyDroop{1e10};
  s.effects.external_leakage = ExternalLeakage{1e-12, 2};
  s.effects.sensor_lag = SensorLag{0.004, PressureChannel::p2};
  s.params.m = 8.0;
  s.sensors.enabled = false;
  EXPECT_LT(integration_step(s), automatic_integration_step(s.params, {}, s.sample_rate_hz));
  const Difference d = halving_difference(s);
  EXPECT_LT(d.pressure, 0.1 * s.sensors.pressure_lsb());
  EXPECT_LT(d.position, 0.1 * s.sensors.position_resolution);
}

// Continuity with constant beta is conservation of fluid mass with density
// rho(p) = rho0 exp(p / beta): d/dt (V_i exp(p_i / beta)) = exp(p_i / beta) q_in,i. The plant
// integrates the right side (its ledger); the left side is computed here from the states.
TEST(MassBalance, IntegratedFlowsMatchVolumeChangesToOnePartPerMillion) {
  Parameters params;
  Effects effects;
  effects.internal_leakage = InternalLeakage{2e-12, 0.5, 0.0};
  effects.external_leakage = ExternalLeakage{1e-12, 1};
  Plant plant(params, effects, 3, 2.5e-4);
  plant.enable_ledger(true);
  const auto content = [&](const PlantState& s, int chamber) {
    const double V = chamber == 1 ? params.V0() + params.A() * s.x : params.V0() - params.A() * s.x;
    return V * std::exp((chamber == 1 ? s.p1 : s.p2) / params.beta);
  };
  const PlantState start = plant.state();
  double worst[2] = {0.0, 0.0}, scale[2] = {0.0, 0.0};
  double min_pressure = params.ps;
  for (int k = 0; k < 2500; ++k) {
    const double t = k * 0.002;
    const double u = 3.0 * std::sin(2.0 * std::numbers::pi * 2.0 * t) + 1.0;
    plant.advance(u, t, 0.002);
    const PlantState& s = plant.state();
    min_pressure = std::min({min_pressure, s.p1, s.p2});
    const double in[2] = {s.mass_in1, s.mass_in2};
    for (int c = 0; c < 2; ++c) {
      const double change = content(s, c + 1) - content(start, c + 1);
      worst[c] = std::max(worst[c], std::abs(change - in[c]));
      scale[c] = std::max(scale[c], std::abs(in[c]));
    }
  }
  ASSERT_GT(min_pressure, 0.0) << "the cavitation clamp would break conservation";
  for (int c = 0; c < 2; ++c) {
    ASSERT_GT(scale[c], 1e-5) << "the run must move fluid (m^3 scale)";
    EXPECT_LT(worst[c] / scale[c], 1e-6) << "chamber " << c + 1;
  }
  // The leak takes out of chamber 1 what it puts into chamber 2.
  EXPECT_GT(plant.state().leaked_volume, 0.0);
}

// At rest under the spring the piston force balance is A (p1 - p2) = K_s x, and with a leak
// the valve supplies exactly the leak flow C_L (p1 - p2) = C_L K_s x / A. The fault-tolerant
// controller's integrator brings the loop to rest at the reference.
TEST(StaticEquilibrium, SpringBalanceAndSteadyLeakFlowMatchAnalyticValues) {
  for (const double C_L : {0.0, 2.0e-12}) {
    Scenario s = testing::held_level(0.04, 30.0, ControllerKind::fault_tolerant, 2);
    if (C_L > 0.0) s.effects.internal_leakage = InternalLeakage{C_L, 0.0, 0.0};
    Rig rig(s);
    RigSample last{};
    for (std::uint64_t k = 0; k < s.samples(); ++k) last = rig.step();
    const Parameters& p = s.params;
    const PlantState& state = rig.plant().state();
    ASSERT_NEAR(std::abs(last.xref), 0.04, 1e-12);
    EXPECT_NEAR(state.x, last.xref, 1e-6);
    EXPECT_NEAR(state.v, 0.0, 1e-7);
    const double spring = p.K_s * state.x;
    EXPECT_NEAR(p.A() * (state.p1 - state.p2), spring, 1e-4 * std::abs(spring));
    const PlantFlows f = rig.plant().flows();
    const double analytic_leak = C_L * spring / p.A();
    EXPECT_NEAR(f.q_int, analytic_leak, 1e-4 * std::abs(analytic_leak) + 1e-15);
    // Nothing moves, so the valve feeds chamber 1 exactly what leaves it.
    EXPECT_NEAR(f.q1, f.q_int + f.q_ext1, 1e-4 * std::abs(analytic_leak) + 1e-12);
    EXPECT_NEAR(f.q2, -f.q_int + f.q_ext2, 1e-4 * std::abs(analytic_leak) + 1e-12);
  }
}

// Rest with no command and no noise is an equilibrium: nothing moves from
// x = v = xs = 0, p1 = p2 = (ps + pt)/2.
TEST(StaticEquilibrium, RestStateStaysAtRest) {
  Parameters p;
  p.sigma_w = 0.0;
  Plant plant(p, {}, 1, 2.5e-4);
  for (int k = 0; k < 1000; ++k) plant.advance(0.0, k * 0.002, 0.002);
  EXPECT_NEAR(plant.state().x, 0.0, 1e-12);
  EXPECT_NEAR(plant.state().p1, 0.5 * (p.ps + p.pt), 1e-3);
  EXPECT_NEAR(plant.state().p2, 0.5 * (p.ps + p.pt), 1e-3);
}

class ShortStability : public ::testing::TestWithParam<std::tuple<ControllerKind, std::uint64_t>> {
};

// Both controllers track the random reference without drifting or oscillating, healthy and
// leaking (the multi-minute version is long_stability_test).
TEST_P(ShortStability, TracksTheReferenceHealthyAndLeaking) {
  const auto [kind, seed] = GetParam();
  Scenario s = preset(kind == ControllerKind::basic ? "healthy" : "healthy-ft", seed);
  s.effects.internal_leakage = InternalLeakage{2.5e-12, 30.0, 0.0};
  const auto samples = testing::run(s);
  double worst_x = 0.0, square_error = 0.0, late_square_error = 0.0;
  std::size_t saturated = 0, late = 0;
  for (const auto& r : samples) {
    worst_x = std::max(worst_x, std::abs(r.x_true));
    square_error += (r.x_true - r.xref) * (r.x_true - r.xref);
    if (std::abs(r.u) >= 10.0) ++saturated;
    ASSERT_GE(r.p1_true, 0.0);
    ASSERT_LE(r.p1_true, s.params.ps * 1.05);
    ASSERT_LE(r.p2_true, s.params.ps * 1.05);
  }
  for (std::size_t k = samples.size() - 5000; k < samples.size(); ++k) {
    late_square_error += std::pow(samples[k].x_true - samples[k].xref, 2);
    ++late;
  }
  EXPECT_LT(worst_x, 0.06);  // references reach 0.05 m; overshoot stays small
  EXPECT_LT(std::sqrt(square_error / samples.size()), 0.012);
  EXPECT_LT(std::sqrt(late_square_error / late), 0.012);
  EXPECT_LT(saturated, samples.size() / 20);  // saturation only at the steps
}

INSTANTIATE_TEST_SUITE_P(Controllers, ShortStability,
                         ::testing::Combine(::testing::Values(ControllerKind::basic,
                                                              ControllerKind::fault_tolerant),
                                            ::testing::Values(1u, 2u, 3u)));

}  // namespace
}  // namespace leakmon::sim
