// The supply seen through one chamber's hold levels: two clusters mirrored around mid-supply
// (ps + pt) / 2, a step of mid-supply found from the first hold that fits neither, and the new
// level read from the holds after it.
#include "detect/chamber_supply_tracker.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace leakmon::detect {
namespace {

constexpr double kHop = 0.04;

// The paper's programme on a chamber: holds of 0.5-4 s at mid +- 1.6-3.2 MPa (the spring load's
// half at 25-50 mm), one moving hop between holds, 1 kPa of hop-mean noise.
struct ChamberRig {
  std::mt19937_64 rng{7};
  double t = 0.0;
  double mid = 8.65e6;
  bool one_sided = false;
  double offset = 0.0, hold_left = 0.0;

  // Runs until `until`, mid-supply following `mid_at`; every event with its time.
  template <class MidAt>
  std::vector<std::pair<ChamberSupplyTracker::Event, double>> run(ChamberSupplyTracker& tracker,
                                                                  double until, MidAt mid_at) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 1e3);
    std::vector<std::pair<ChamberSupplyTracker::Event, double>> events;
    while (t < until - 1e-9) {
      t += kHop;
      bool still = true;
      if (hold_left <= 0.0) {  // the move to the next level: one hop
        const double sign = one_sided || u(rng) < 0.5 ? 1.0 : -1.0;
        offset = sign * (1.6e6 + 1.6e6 * u(rng));
        hold_left = 0.5 + 3.5 * u(rng);
        still = false;
      }
      hold_left -= kHop;
      // A supply ramp moves the chamber while it rests: the hop is not still.
      still = still && std::abs(mid_at(t) - mid_at(t - kHop)) < 5e3;
      const auto e = tracker.add(t, mid_at(t) + offset + noise(rng), still);
      if (e != ChamberSupplyTracker::Event::none) events.emplace_back(e, t);
    }
    return events;
  }
};

TEST(ChamberSupplyTracker, FindsAStepAndReadsTheNewSupply) {
  ChamberSupplyTracker tracker;
  ChamberRig rig;
  auto steady = [&](double) { return rig.mid; };
  EXPECT_TRUE(rig.run(tracker, 90.0, steady).empty());
  ASSERT_TRUE(tracker.learn());
  EXPECT_TRUE(tracker.active());
  EXPECT_TRUE(rig.run(tracker, 600.0, steady).empty()) << "healthy holds all fit";
  // The supply lowered from 17.2 to 14 MPa over 2 s at 600 s: mid-supply falls by 1.6 MPa.
  auto lowered = [&](double t) {
    return rig.mid - 1.6e6 * std::clamp((t - 600.0) / 2.0, 0.0, 1.0);
  };
  const auto events = rig.run(tracker, 700.0, lowered);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].first, ChamberSupplyTracker::Event::step);
  EXPECT_LT(events[0].second, 610.0);
  EXPECT_EQ(events[1].first, ChamberSupplyTracker::Event::estimated);
  EXPECT_LT(events[1].second, 660.0);
  // Three holds a side: each cluster's mean within 0.46 MPa / sqrt(3), mid-supply's std. dev.
  // about 0.19 MPa; two of them.
  EXPECT_NEAR(tracker.mid_shift(), -1.6e6, 0.4e6);
  EXPECT_FALSE(tracker.awaiting());
  // Dated to the last hold before the ramp (holds after it that fitted by chance do not count).
  EXPECT_LE(tracker.step_time(), 600.0 + kHop);
  EXPECT_GT(tracker.step_time(), 595.0);
  // And raised to 20 MPa in one go: mid-supply 3 MPa up.
  auto raised = [&](double t) { return t < 800.0 ? lowered(t) : rig.mid + 1.4e6; };
  const auto again = rig.run(tracker, 900.0, raised);
  ASSERT_EQ(again.size(), 2u);
  EXPECT_NEAR(tracker.mid_shift(), 1.4e6, 0.4e6);
}

TEST(ChamberSupplyTracker, AOneSidedProgrammeIsNotUsed) {
  ChamberSupplyTracker tracker;
  ChamberRig rig;
  rig.one_sided = true;
  rig.run(tracker, 90.0, [&](double) { return rig.mid; });
  EXPECT_FALSE(tracker.learn());
  EXPECT_FALSE(tracker.active());
  EXPECT_TRUE(
      rig.run(tracker, 300.0, [&](double t) { return rig.mid - (t > 200 ? 2e6 : 0.0); }).empty());
  EXPECT_EQ(tracker.mid_shift(), 0.0);
}

TEST(ChamberSupplyTracker, StateRoundTripsWhileAwaitingANewLevel) {
  ChamberSupplyTracker a;
  ChamberRig rig;
  auto mid_at = [&](double t) { return rig.mid + (t > 200.0 ? 1.5e6 : 0.0); };
  rig.run(a, 90.0, mid_at);
  ASSERT_TRUE(a.learn());
  std::vector<std::pair<ChamberSupplyTracker::Event, double>> seen;
  while (!a.awaiting() && rig.t < 260.0) {
    for (const auto& e : rig.run(a, rig.t + kHop, mid_at)) seen.push_back(e);
  }
  ASSERT_TRUE(a.awaiting());
  ChamberSupplyTracker b;
  DetectorState saved("probe", 1);
  a.save(saved, "chamber");
  b.restore(DetectorState::parse(saved.text()), "chamber");
  EXPECT_TRUE(b.awaiting());
  EXPECT_EQ(b.step_time(), a.step_time());
  ChamberRig twin = rig;  // the same data follows for both
  const auto after_a = rig.run(a, 400.0, mid_at);
  const auto after_b = twin.run(b, 400.0, mid_at);
  EXPECT_EQ(after_a, after_b);
  ASSERT_FALSE(after_a.empty());
  EXPECT_EQ(a.mid_shift(), b.mid_shift());

  // Every value has a name; a ring that does not fit and a count out of range do not load.
  DetectorState named("probe", 1);
  a.save(named, "chamber");
  EXPECT_TRUE(named.has("chamber.learned_mid"));
  EXPECT_TRUE(named.has("chamber.holds.level"));
  DetectorState shorter = named;
  auto levels = shorter.get_list("chamber.holds.level");
  levels.pop_back();
  shorter.put("chamber.holds.level", levels);
  EXPECT_THROW(b.restore(shorter, "chamber"), StateError);
  DetectorState beyond = named;
  beyond.put_count("chamber.holds.next", 1000000000);
  EXPECT_THROW(b.restore(beyond, "chamber"), StateError);
  ChamberSupplyTracker small(16);
  EXPECT_THROW(small.restore(named, "chamber"), StateError) << "a ring of another size";
}

}  // namespace
}  // namespace leakmon::detect
