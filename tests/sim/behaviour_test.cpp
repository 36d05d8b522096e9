// The behaviour the paper reports, asserted on the simulator with its noise and sensors on:
// under the basic controller a leak leaves a steady-state position error under load; the
// fault-tolerant controller removes it, and its command instead carries an offset that grows
// with the load pressure.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/rig.hpp"
#include "tests/sim/sim_test_support.hpp"

namespace leakmon::sim {
namespace {

struct SteadyState {
  double error;          // mean x - xref over the last 4 s, signed towards the load
  double command;        // mean u over the last 4 s, signed towards the load
  double load_pressure;  // mean |p1 - p2|
};

SteadyState settle(ControllerKind kind, double amplitude, double C_L) {
  Scenario s = testing::held_level(amplitude, 12.0, kind, 4);
  s.params.sigma_w = Parameters::nominal().sigma_w;  // the realistic noisy valve
  s.sensors = SensorSettings{};                      // and real sensors
  if (C_L > 0.0) s.effects.internal_leakage = InternalLeakage{C_L, 0.0, 0.0};
  const auto run = testing::run(s);
  const double sign = run.back().xref > 0.0 ? 1.0 : -1.0;
  return {sign * testing::mean_over(run, 8.0, 12.0,
                                    [](const RigSample& r) { return r.x_true - r.xref; }),
          sign * testing::mean_over(run, 8.0, 12.0, [](const RigSample& r) { return r.u; }),
          testing::mean_over(run, 8.0, 12.0,
                             [](const RigSample& r) { return std::abs(r.p1_true - r.p2_true); })};
}

constexpr double kPaperLeak = 2.0e-12;  // 0.12 l/min/MPa

TEST(PaperBehaviour, BasicControllerLeavesASteadyStateErrorUnderLoadWithALeak) {
  const SteadyState healthy = settle(ControllerKind::basic, 0.05, 0.0);
  const SteadyState leaking = settle(ControllerKind::basic, 0.05, kPaperLeak);
  const SteadyState leaking_light = settle(ControllerKind::basic, 0.025, kPaperLeak);
  // The spring pulls the piston back: the leak lets it sag short of the reference.
  EXPECT_LT(leaking.error, -0.3e-3);
  EXPECT_LT(leaking.error, 2.0 * healthy.error);
  // The error comes from the leak flow C_L (p1 - p2), so it grows with the load.
  EXPECT_GT(leaking.load_pressure, 1.8 * leaking_light.load_pressure);
  EXPECT_LT(leaking.error, 1.6 * leaking_light.error);
}

TEST(PaperBehaviour, FaultTolerantControllerRemovesTheErrorButItsCommandCarriesAnOffset) {
  const SteadyState healthy = settle(ControllerKind::fault_tolerant, 0.05, 0.0);
  const SteadyState leaking = settle(ControllerKind::fault_tolerant, 0.05, kPaperLeak);
  const SteadyState leaking_light = settle(ControllerKind::fault_tolerant, 0.025, kPaperLeak);
  const SteadyState basic_leaking = settle(ControllerKind::basic, 0.05, kPaperLeak);
  // Integral action: no steady-state error, leak or not (within the 10 um position LSB).
  EXPECT_LT(std::abs(leaking.error), 10e-6);
  EXPECT_LT(std::abs(leaking.error), 0.05 * std::abs(basic_leaking.error));
  // The command holds the valve open to feed the leak: an offset beyond the healthy one that
  // grows with the load pressure.
  EXPECT_GT(leaking.command - healthy.command, 0.05);
  EXPECT_GT(leaking.command, 1.5 * leaking_light.command);
  EXPECT_GT(leaking.load_pressure, 1.8 * leaking_light.load_pressure);
}

}  // namespace
}  // namespace leakmon::sim
