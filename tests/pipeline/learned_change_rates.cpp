// Measurement, not a test (docs/detection.md "A leak during learning"): how often replay_capture
// with the built-in defaults writes `learned_change` on 20 healthy 100 s captures that drift
// while the detector learns (MODEL.md "Drifting operating conditions": cold starts, cooler
// cycles, supply changes and both, in turn, without a `temp` column; both controllers), and on
// 12 captures of 120 s whose leak (1e-12 to 5e-12, or 1e-11 for the pressures alone) opens at
// 50, 65 or 80 s. Each capture twice: all columns (flow balance) and t, p1, p2 (pressure-only).
//   build/bin/learned_change_rates
#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "io/event_json.hpp"
#include "pipeline/replay.hpp"
#include "sim/simulate.hpp"
#include "tests/support/capture_slices.hpp"

using namespace leakmon;

namespace {

const io::Event* learned_change(const pipeline::ReplayResult& result) {
  for (const auto& e : result.events) {
    if (e.kind == io::EventKind::learned_change) return &e;
  }
  return nullptr;
}

std::string verdict(const capture::Capture& capture, int& fired) {
  const auto result = pipeline::replay_capture(capture, pipeline::default_replay_config(capture));
  const io::Event* e = learned_change(result);
  if (e == nullptr) return "-";
  ++fired;
  const std::string size =
      e->feature == "index" ? fmt::format("{:.1f} -> {:.1f} kPa", e->baseline / 1e3, e->index / 1e3)
                            : fmt::format("{:.2e} m^3/(s Pa)", e->leak_coefficient);
  return fmt::format("{} {} at {:.1f} s, {}", e->feature, e->channel, e->change_t, size);
}

}  // namespace

int main() {
  // One event as the event log writes it, for docs/daemon.md.
  {
    sim::Scenario s;
    s.seed = 7;
    s.duration_s = 120.0;
    s.effects.internal_leakage = sim::InternalLeakage{2e-12, 70.0, 0.0};
    const auto capture = sim::simulate(s);
    const auto result = pipeline::replay_capture(capture, pipeline::default_replay_config(capture));
    if (const io::Event* e = learned_change(result)) fmt::print("{}\n", io::to_json_line(*e));
  }
  int healthy_flow = 0, healthy_pressure = 0;
  for (int i = 0; i < 20; ++i) {
    sim::Scenario s;
    s.seed = 100 + static_cast<std::uint64_t>(i);
    s.duration_s = 100.0;
    s.controller = i % 2 == 0 ? sim::ControllerKind::basic : sim::ControllerKind::fault_tolerant;
    sim::TemperatureProfile profile;
    std::string what;
    switch (i % 4) {
      case 0:
        profile.kind = sim::TemperatureProfile::Kind::warm_up;
        profile.T0 = 15.0 + (i * 7) % 11;
        profile.T_work = 50.0;
        profile.tau_s = 200.0 + 40.0 * i;
        s.conditions.temperature = profile;
        what = fmt::format("warm-up from {:.0f} degC, tau {:.0f} s", profile.T0, profile.tau_s);
        break;
      case 1:
        profile.kind = sim::TemperatureProfile::Kind::cooler;
        profile.T_work = 45.0;
        profile.amplitude = 2.0 + i % 3;
        profile.period_s = 150.0 + 20.0 * i;
        s.conditions.temperature = profile;
        what = fmt::format("cooler +-{:.0f} K, {:.0f} s", profile.amplitude, profile.period_s);
        break;
      case 2: {
        const double t_s = 40.0 + 3.0 * i, ps = 13e6 + 1e5 * i;
        s.conditions.supply = {{t_s, ps, 2.0}};
        what = fmt::format("supply to {:.1f} MPa at {:.0f} s", ps / 1e6, t_s);
        break;
      }
      default:
        profile.kind = sim::TemperatureProfile::Kind::warm_up_cooler;
        profile.T0 = 25.0;
        profile.T_work = 48.0;
        profile.tau_s = 300.0;
        profile.amplitude = 2.0;
        profile.period_s = 200.0;
        s.conditions.temperature = profile;
        what = "warm-up 25 -> 48 degC and cooler";
    }
    const auto capture = sim::simulate(s);
    const std::string flow = verdict(capture, healthy_flow);
    const std::string pressure =
        verdict(test::columns_of(capture, {"t", "p1", "p2"}), healthy_pressure);
    fmt::print("healthy {:2d} {:38s} | flow: {:28s} | pressure: {}\n", i, what, flow, pressure);
  }
  int leak_flow = 0, leak_pressure = 0;
  const double sizes[] = {1e-12, 2e-12, 3.5e-12, 5e-12};
  const double onsets[] = {50.0, 65.0, 80.0};
  for (int i = 0; i < 12; ++i) {
    for (const bool pressures_only : {false, true}) {
      sim::Scenario s;
      s.seed = 200 + static_cast<std::uint64_t>(i);
      s.duration_s = 120.0;
      s.controller = i % 2 == 0 ? sim::ControllerKind::basic : sim::ControllerKind::fault_tolerant;
      const double c_l = pressures_only ? 1e-11 : sizes[i % 4];
      s.effects.internal_leakage = sim::InternalLeakage{c_l, onsets[i / 4], 0.0};
      const auto capture = sim::simulate(s);
      const std::string v =
          pressures_only ? verdict(test::columns_of(capture, {"t", "p1", "p2"}), leak_pressure)
                         : verdict(capture, leak_flow);
      fmt::print("leak {:2d} C_L {:.1e} at {:.0f} s {:14s} | {}\n", i, c_l, onsets[i / 4],
                 pressures_only ? "pressure-only" : "flow", v);
    }
  }
  fmt::print("healthy: flow {}/20 reported, pressure-only {}/20\n", healthy_flow, healthy_pressure);
  fmt::print("leak in learning: flow {}/12 reported, pressure-only (1e-11) {}/12\n", leak_flow,
             leak_pressure);
  return 0;
}
