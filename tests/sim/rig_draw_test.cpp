// Other rigs for evaluations (sim/rig_draw.hpp): draws lie in MODEL.md's "Other rigs" ranges,
// are reproducible by seed and run under the paper's controllers; rigs the loop cannot hold are
// refused with a reason; mis-stated descriptions change exactly one value.
#include "sim/rig_draw.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "sim/simulate.hpp"

namespace leakmon::sim {
namespace {

TEST(RigDraw, DrawsLieInModelMdRangesAndRun) {
  std::set<int> grades;
  int without_spring = 0, out_of_band = 0;
  for (std::uint64_t seed = 1; seed <= 24; ++seed) {
    const auto controller = seed % 2 ? ControllerKind::basic : ControllerKind::fault_tolerant;
    const OtherRig rig = draw_other_rig(seed, controller);
    const Parameters& p = rig.rig.params;
    EXPECT_GE(p.D, 0.025);
    EXPECT_LE(p.D, 0.100);
    EXPECT_GE(p.d / p.D, 0.4 - 1e-12);
    EXPECT_LE(p.d / p.D, 0.7 + 1e-12);
    EXPECT_GE(p.L, 0.1);
    EXPECT_LE(p.L, 1.0);
    EXPECT_GE(p.ps, 7e6);
    EXPECT_LE(p.ps, 28e6);
    EXPECT_LE(p.pt, 1e6);
    EXPECT_GE(p.beta, 0.5e9);
    EXPECT_LE(p.beta, 1.5e9);
    EXPECT_GE(p.m, 2.0);
    EXPECT_LE(p.m, 500.0);
    EXPECT_GE(p.b, 50.0);
    EXPECT_LE(p.b, 5000.0);
    EXPECT_LE(p.K_s, 500e3);
    EXPECT_GE(p.Kv, 5e-8);
    EXPECT_LE(p.Kv, 3e-6);
    EXPECT_GE(p.tau, 1e-3);
    EXPECT_LE(p.tau, 20e-3);
    EXPECT_GE(p.C_n, 1e-13);
    EXPECT_LE(p.C_n, 2e-12);
    EXPECT_GE(rig.sensors.pressure_full_scale, 1.15 * p.ps);
    EXPECT_LE(rig.reference.amp_max, 0.35 * p.L + 1e-12);
    EXPECT_GE(rig.reference.amp_max, 5e-3);
    EXPECT_TRUE(rig.rig.states("supply_pressure"));
    EXPECT_TRUE(rig.rig.states("oil_grade"));
    grades.insert(static_cast<int>(std::lround(rig.rig.oil.nu40())));
    without_spring += p.K_s == 0.0 ? 1 : 0;
    const double mode = hydraulic_mode_hz(p);
    out_of_band += mode < 62.5 || mode > 125.0 ? 1 : 0;
    // The drawn rig runs on a reference it was not drawn with. How often the valve saturates
    // depends on the steps drawn (3.5-4.5 % on this one where the draw saw under 3 %): that
    // bar gets room, the loop's own (stops, tracking, ringing) does not.
    ViabilityLimits fresh;
    fresh.max_saturated = 0.08;
    const Viability v =
        check_viability(other_rig_scenario(rig, controller, 12.0, seed + 99), 12.0, fresh);
    EXPECT_TRUE(v.ok) << "seed " << seed << ": " << v.reason;
  }
  // The draws span the ranges: several oils, and rigs whose hydraulic mode leaves the index's
  // 62.5-125 Hz band (what the pressure-only detectors must say).
  EXPECT_GE(grades.size(), 2u);
  EXPECT_GE(out_of_band, 4);
  EXPECT_LE(without_spring, 12);
}

TEST(RigDraw, ReproducibleBySeed) {
  const OtherRig a = draw_other_rig(42, ControllerKind::basic);
  const OtherRig b = draw_other_rig(42, ControllerKind::basic);
  const OtherRig c = draw_other_rig(43, ControllerKind::basic);
  EXPECT_EQ(a.rig.params.D, b.rig.params.D);
  EXPECT_EQ(a.rig.params.Kv, b.rig.params.Kv);
  EXPECT_EQ(a.reference.amp_max, b.reference.amp_max);
  EXPECT_NE(a.rig.params.D, c.rig.params.D);
}

TEST(RigDraw, ThePapersRig) {
  const Parameters paper = Parameters::nominal();
  // MODEL.md: "the hydraulic mode sits near 75 Hz".
  EXPECT_NEAR(hydraulic_mode_hz(paper), 75.0, 3.0);
  EXPECT_EQ(max_step_amplitude(paper), 0.05);
  EXPECT_EQ(sensors_for(paper).pressure_full_scale, 20.7e6);
  Scenario s;
  EXPECT_TRUE(check_viability(s).ok) << check_viability(s).reason;
}

TEST(RigDraw, RigsTheLoopCannotHoldAreRefused) {
  // Ten times the paper's valve on the paper's cylinder: the loop gain is ten times what the
  // controllers were designed for.
  Scenario big_valve;
  big_valve.params.Kv *= 10.0;
  const Viability v = check_viability(big_valve);
  EXPECT_FALSE(v.ok);
  EXPECT_FALSE(v.saturated) << v.reason;
  EXPECT_FALSE(v.reason.empty());
  // A stroke shorter than the paper's steps: the piston meets its stops.
  Scenario short_stroke;
  short_stroke.params.L = 0.08;
  const Viability stops = check_viability(short_stroke);
  EXPECT_FALSE(stops.ok);
  EXPECT_NE(stops.reason.find("end stop"), std::string::npos) << stops.reason;
}

TEST(RigDraw, AmplitudeFitsStrokeAndForce) {
  Parameters p;
  p.L = 0.1;
  EXPECT_NEAR(max_step_amplitude(p), 0.035, 1e-12);
  p = Parameters::nominal();
  p.K_s = 400e3;  // 0.45 A (ps - pt) / K_s = 12 mm
  EXPECT_NEAR(max_step_amplitude(p), 0.45 * p.A() * (p.ps - p.pt) / p.K_s, 1e-12);
  EXPECT_LT(max_step_amplitude(p), 0.013);
  p.ps = 25e6;
  EXPECT_EQ(sensors_for(p).pressure_full_scale, 35e6);
}

TEST(RigDraw, MisstatedDescriptionChangesOneValue) {
  const OtherRig rig = draw_other_rig(7, ControllerKind::basic);
  const RigDescription stated = misstate(rig.rig, "supply_pressure", 1.2);
  EXPECT_DOUBLE_EQ(stated.params.ps, 1.2 * rig.rig.params.ps);
  EXPECT_EQ(stated.params.K_s, rig.rig.params.K_s);
  EXPECT_EQ(stated.params.Kv, rig.rig.params.Kv);
  EXPECT_EQ(stated.stated.size(), rig.rig.stated.size());
  const RigDescription stiff = misstate(RigDescription::paper(), "load_stiffness", 0.5);
  EXPECT_EQ(stiff.params.K_s, 40e3);
  EXPECT_EQ(stiff.stated, std::vector<std::string>{"load_stiffness"});
  EXPECT_THROW(misstate(stated, "oil_grade", 2.0), std::invalid_argument);
  EXPECT_THROW(misstate(stated, "colour", 2.0), std::invalid_argument);
}

TEST(RigDraw, ScenarioCarriesTheRig) {
  const OtherRig rig = draw_other_rig(3, ControllerKind::fault_tolerant);
  const capture::Capture capture =
      simulate(other_rig_scenario(rig, ControllerKind::fault_tolerant, 1.0, 5));
  EXPECT_EQ(capture.rows(), 500u);
  bool listed = false;
  for (const auto& [key, value] : capture.metadata) listed = listed || key == "rig";
  EXPECT_TRUE(listed);
  // At rest the chambers sit near the drawn supply's middle, read in the drawn range.
  EXPECT_NEAR(capture.column("p1")[0], 0.5 * (rig.rig.params.ps + rig.rig.params.pt),
              0.05 * rig.rig.params.ps);
}

}  // namespace
}  // namespace leakmon::sim
