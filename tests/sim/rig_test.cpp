// The closed-loop rig's step API: allocation-free (the daemon's sim driver runs it on the
// real-time thread), reproducible from its seed, leak injectable at run time; and the batch
// API's capture.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/rig.hpp"
#include "sim/simulate.hpp"
#include "tests/sim/sim_test_support.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::sim {
namespace {

Scenario everything_on() {
  Scenario s = preset("paper-fig10", 4);
  s.duration_s = 4.0;
  s.effects.internal_leakage->onset_s = 2.0;
  for (const auto name : Effects::names()) {
    if (name != "internal_leakage") s.effects.enable(name);
  }
  return s;
}

TEST(RigStep, AllocatesNothingWithEveryEffectActive) {
  const Scenario s = everything_on();
  ASSERT_EQ(s.effects.describe().size(), 11u);
  Rig rig(s);  // allocation is allowed here only
  double checksum = 0.0;
  {
    test::AllocationScope scope;
    for (std::uint64_t k = 0; k < s.samples(); ++k) checksum += rig.step().p1;
    rig.set_internal_leak(4e-12, 3.0, 0.5);
    for (std::uint64_t k = 0; k < 500; ++k) checksum += rig.step().p1;
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_TRUE(std::isfinite(checksum));
  EXPECT_GT(checksum, 0.0);
}

TEST(RigStep, ProducesTheConventionsSampleSequence) {
  Scenario s = preset("healthy", 5);
  s.duration_s = 1.0;
  Rig rig(s);
  const RigSample first = rig.step();
  // Rest state at t = 0, measured before anything moves.
  EXPECT_EQ(first.t, 0.0);
  EXPECT_EQ(first.x_true, 0.0);
  EXPECT_EQ(first.p1_true, 0.5 * (s.params.ps + s.params.pt));
  EXPECT_NE(first.xref, 0.0);  // the first level starts at t = 0
  EXPECT_NE(first.u, 0.0);     // computed from the measured position at t = 0
  const RigSample second = rig.step();
  EXPECT_DOUBLE_EQ(second.t, 0.002);
  EXPECT_EQ(rig.index(), 2u);
}

TEST(RigStep, SameSeedSameRunDifferentSeedDifferentRun) {
  Scenario s = everything_on();
  const auto a = testing::run(s);
  const auto b = testing::run(s);
  s.seed += 1;
  const auto c = testing::run(s);
  bool differs = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].p1, b[k].p1);
    ASSERT_EQ(a[k].u, b[k].u);
    differs |= a[k].p1 != c[k].p1;
  }
  EXPECT_TRUE(differs);
  Rig rig(everything_on());
  for (int k = 0; k < 100; ++k) rig.step();
  rig.reset();
  EXPECT_EQ(rig.step().p1, a[0].p1);
  EXPECT_EQ(rig.step().p1, a[1].p1);
}

TEST(RigStep, LeakCanBeInjectedAndHealedAtRunTime) {
  Scenario s = preset("healthy", 6);
  s.duration_s = 6.0;
  Rig rig(s);
  rig.set_internal_leak(2e-12, 2.0, 0.0);
  double max_before = 0.0, max_after = 0.0;
  for (std::uint64_t k = 0; k < s.samples(); ++k) {
    const RigSample r = rig.step();
    if (r.t < 2.0) max_before = std::max(max_before, std::abs(r.q_int));
    if (r.t >= 2.0) {
      max_after = std::max(max_after, std::abs(r.q_int));
      ASSERT_NEAR(r.q_int, 2e-12 * (r.p1_true - r.p2_true), 1e-20 + 1e-9 * std::abs(r.q_int));
    }
  }
  EXPECT_EQ(max_before, 0.0);
  EXPECT_GT(max_after, 1e-6);
  rig.set_internal_leak(0.0, 0.0);
  EXPECT_EQ(rig.step().q_int, 0.0);
}

// Scenario::change (issue 24: effects that appear inside a capture): the run is the plain one
// up to the change, then the one with the effects on, without allocating; a transducer offset
// appears in the readings at that sample and metadata names the change.
TEST(RigStep, EffectsAppearAtTheirChange) {
  Scenario plain = preset("healthy", 7);
  plain.duration_s = 4.0;
  Scenario changed = plain;
  Effects appearing;
  appearing.enable("sensor_offset", std::vector<EffectParameter>{{"offset", 2e5}});
  appearing.enable("coulomb_friction", std::vector<EffectParameter>{{"F_C", 150.0}});
  changed.change = EffectChange{2.0, appearing};
  const auto a = testing::run(plain);
  Rig rig(changed);
  std::vector<RigSample> b;
  b.reserve(changed.samples());
  {
    test::AllocationScope scope;
    for (std::uint64_t k = 0; k < changed.samples(); ++k) b.push_back(rig.step());
    EXPECT_EQ(scope.count(), 0u);
  }
  ASSERT_EQ(a.size(), b.size());
  bool moved_later = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (b[k].t < 2.0) {
      ASSERT_EQ(a[k].p1, b[k].p1) << b[k].t;
      ASSERT_EQ(a[k].x_true, b[k].x_true) << b[k].t;
    } else if (b[k].t == 2.0) {
      // Same plant state, the offset on the reading (within the 12-bit quantisation).
      EXPECT_EQ(a[k].p1_true, b[k].p1_true);
      EXPECT_NEAR(b[k].p1 - a[k].p1, 2e5, 6e3);
    } else {
      moved_later |= a[k].x_true != b[k].x_true;  // the friction acts
    }
  }
  EXPECT_TRUE(moved_later);
  rig.reset();
  EXPECT_EQ(rig.step().p1, a[0].p1);
  const auto meta = capture_metadata(changed);
  bool named = false;
  for (const auto& [key, value] : meta) {
    if (key == "effect_change") {
      named = true;
      EXPECT_NE(value.find("t_s=2"), std::string::npos) << value;
      EXPECT_NE(value.find("sensor_offset"), std::string::npos) << value;
    }
  }
  EXPECT_TRUE(named);
}

TEST(BatchSimulation, WritesTheCaptureColumnsAndMetadata) {
  Scenario s = everything_on();
  s.params.beta = 6e8;
  const capture::Capture capture = simulate(s);
  EXPECT_EQ(capture.columns,
            (std::vector<std::string>{"t", "xref", "u", "x", "p1", "p2", "q_int"}));
  EXPECT_EQ(capture.rows(), 2000u);
  EXPECT_EQ(capture.sample_rate_hz(), 500.0);
  EXPECT_EQ(capture.metadata_value("seed"), "4");
  EXPECT_EQ(capture.metadata_value("source"), "sim preset paper-fig10 seed 4");
  EXPECT_EQ(capture.metadata_value("params"), "beta=6e+08");
  int effects = 0;
  for (const auto& [key, value] : capture.metadata) {
    if (key == "effect") ++effects;
    if (key == "effect" && value.rfind("internal_leakage", 0) == 0) {
      EXPECT_NE(value.find("C_L=2e-12"), std::string::npos) << value;
      EXPECT_NE(value.find("onset_s=2"), std::string::npos) << value;
    }
    if (key == "effect" && value.rfind("sensor_lag", 0) == 0) {
      EXPECT_NE(value.find("channel=p1"), std::string::npos) << value;
    }
  }
  EXPECT_EQ(effects, 11);
  // Same numbers as the step API.
  const auto steps = testing::run(s);
  EXPECT_EQ(capture.column("p2")[1234], steps[1234].p2);
  EXPECT_EQ(capture.column("q_int")[1999], steps[1999].q_int);
}

}  // namespace
}  // namespace leakmon::sim
