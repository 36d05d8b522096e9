// The flow balance on the simulated rig of MODEL.md (sim/) while its oil warms up, cycles with
// the cooler and its supply set-point moves: hop means as the daemon forms them (the daemon's
// own path is covered by the replay tests), fed straight to the detector.
#include <gtest/gtest.h>

#include <cmath>

#include "detect/flow_balance_detector.hpp"
#include "sim/simulate.hpp"

namespace leakmon::detect {
namespace {

constexpr std::size_t kStep = 20;  // samples per hop at 500 Hz
constexpr double kHop = 0.04;

struct Outcome {
  double first_raise = -1.0;
  double max_score_before_onset = 0.0;
  Decision last;
};

Outcome run(const sim::Scenario& scenario, bool use_temp, bool use_ps, double onset) {
  const capture::Capture capture = sim::simulate(scenario);
  FlowBalanceDetector detector(FlowBalanceOptions{}, kHop);
  const auto& t = capture.column("t");
  const auto& u = capture.column("u");
  const auto& x = capture.column("x");
  const auto& p1 = capture.column("p1");
  const auto& p2 = capture.column("p2");
  const std::vector<double>* temp = use_temp ? &capture.column("temp") : nullptr;
  const std::vector<double>* ps = use_ps ? &capture.column("ps") : nullptr;
  Outcome outcome;
  for (std::size_t start = 0; start + kStep <= capture.rows(); start += kStep) {
    auto mean = [&](const std::vector<double>& column) {
      double sum = 0.0;
      for (std::size_t i = start; i < start + kStep; ++i) sum += column[i];
      return sum / static_cast<double>(kStep);
    };
    Observation o;
    o.t = t[start + kStep - 1];
    o.u = mean(u);
    o.x = mean(x);
    o.p1 = mean(p1);
    o.p2 = mean(p2);
    if (temp != nullptr) o.temp = mean(*temp);
    if (ps != nullptr) o.ps = mean(*ps);
    outcome.last = detector.update(o);
    if (std::isnan(outcome.last.score)) continue;
    if (o.t < onset)
      outcome.max_score_before_onset = std::max(outcome.max_score_before_onset, outcome.last.score);
    if (outcome.first_raise < 0.0 && outcome.last.score >= detector.raise_threshold()) {
      outcome.first_raise = o.t;
    }
  }
  return outcome;
}

sim::Scenario warm_up(std::uint64_t seed, sim::ControllerKind controller, double seconds) {
  sim::Scenario s;
  s.controller = controller;
  s.seed = seed;
  s.duration_s = seconds;
  sim::TemperatureProfile profile;
  profile.kind = sim::TemperatureProfile::Kind::warm_up_cooler;
  profile.T0 = 20.0;
  profile.T_work = 50.0;
  profile.tau_s = 300.0;
  profile.amplitude = 3.0;
  profile.period_s = 300.0;
  profile.cooler_start_s = 900.0;
  s.conditions.temperature = profile;
  s.record.temp = true;
  s.record.ps = true;
  return s;
}

TEST(FlowBalanceOnTheSimulatedRig, WarmUpAndCoolerRaiseNothing) {
  for (const auto controller : {sim::ControllerKind::basic, sim::ControllerKind::fault_tolerant}) {
    const sim::Scenario s = warm_up(21, controller, 1500.0);
    for (const bool use_temp : {false, true}) {
      const Outcome o = run(s, use_temp, false, 1e300);
      EXPECT_LT(o.max_score_before_onset, 1.0) << "temp " << use_temp;
      std::printf("controller %d temp %d: max score %.3f, final C_L %.3g +- %.3g\n",
                  static_cast<int>(controller), use_temp, o.max_score_before_onset,
                  o.last.leak_coefficient, o.last.leak_coefficient_ci);
    }
  }
}

TEST(FlowBalanceOnTheSimulatedRig, ALeakAfterTheWarmUpIsFound) {
  sim::Scenario s = warm_up(22, sim::ControllerKind::basic, 1300.0);
  s.effects.internal_leakage = sim::InternalLeakage{1e-12, 1200.0, 0.0};
  for (const bool use_temp : {false, true}) {
    const Outcome o = run(s, use_temp, false, 1200.0);
    std::printf("temp %d: max before %.3f, raise %.1f, C_L %.3g +- %.3g\n", use_temp,
                o.max_score_before_onset, o.first_raise, o.last.leak_coefficient,
                o.last.leak_coefficient_ci);
    EXPECT_LT(o.max_score_before_onset, 1.0);
    EXPECT_GT(o.first_raise, 1200.0);
    EXPECT_LT(o.first_raise, 1260.0);
  }
}

TEST(FlowBalanceOnTheSimulatedRig, SupplyChangesRaiseNothing) {
  sim::Scenario s;
  s.seed = 23;
  s.duration_s = 900.0;
  s.record.ps = true;
  s.conditions.supply = {{300.0, 14e6, 2.0}, {600.0, 20e6, 0.0}};
  for (const bool use_ps : {false, true}) {
    const Outcome o = run(s, false, use_ps, 1e300);
    std::printf("ps %d: max %.3f\n", use_ps, o.max_score_before_onset);
    EXPECT_LT(o.max_score_before_onset, 1.0) << "ps " << use_ps;
  }
}

}  // namespace
}  // namespace leakmon::detect
