// detail_xcorr on synthetic chamber pressures (synthetic_pressures.hpp): a damped 75 Hz mode in
// antiphase plus independent transducer noise; a leak damps the mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "detect/detail_xcorr_detector.hpp"
#include "detect/factory.hpp"
#include "tests/detect/synthetic_pressures.hpp"

namespace leakmon::detect {
namespace {

constexpr AvailableSignals kPressures{true, true, false, false};
constexpr AvailableSignals kP1Alone{true, false, false, false};

struct Outcome {
  double max_healthy_score = 0.0;
  double first_raise = -1.0;  // source time, -1: never
  bool judged = false;
};

Outcome run(Detector& detector, test::SyntheticPressures& rig, double seconds,
            bool p1_alone = false) {
  Outcome out;
  while (rig.t < seconds) {
    Observation o = rig.next();
    if (p1_alone) o.p2_samples = {};
    const Decision d = detector.update(o);
    if (std::isnan(d.score)) continue;
    out.judged = true;
    if (o.t < rig.onset) out.max_healthy_score = std::max(out.max_healthy_score, d.score);
    if (out.first_raise < 0.0 && d.score >= detector.raise_threshold()) out.first_raise = o.t;
  }
  return out;
}

TEST(DetailXcorrDetector, BothChambersUseTheCorrelationOneChamberTheBandRatio) {
  auto both = make_detector("detail_xcorr", kPressures, 0.04, nullptr);
  auto one = make_detector("detail_xcorr", kP1Alone, 0.04, nullptr);
  EXPECT_TRUE(dynamic_cast<DetailXcorrDetector&>(*both).uses_correlation());
  EXPECT_FALSE(dynamic_cast<DetailXcorrDetector&>(*one).uses_correlation());
  EXPECT_EQ(both->name(), "detail_xcorr");
}

TEST(DetailXcorrDetector, QuietWhenHealthyAndRaisesWhenTheModeIsDamped) {
  for (const bool p1_alone : {false, true}) {
    auto detector = make_detector("detail_xcorr", p1_alone ? kP1Alone : kPressures, 0.04, nullptr);
    test::SyntheticPressures rig;
    rig.onset = 400.0;
    // One chamber's band ratio separates less than the two chambers' correlation (as on the
    // simulated rig): it gets a stronger damping.
    rig.leak_pole_radius = p1_alone ? 0.9 : 0.955;
    const Outcome out = run(*detector, rig, 520.0, p1_alone);
    EXPECT_TRUE(out.judged) << p1_alone;
    EXPECT_LT(out.max_healthy_score, 1.0) << p1_alone;
    EXPECT_GT(out.first_raise, rig.onset) << p1_alone;
    EXPECT_LT(out.first_raise, rig.onset + 60.0) << p1_alone;
  }
}

TEST(DetailXcorrDetector, StaysQuietWithoutALeak) {
  auto detector = make_detector("detail_xcorr", kPressures, 0.04, nullptr);
  test::SyntheticPressures rig;
  const Outcome out = run(*detector, rig, 1200.0);
  EXPECT_TRUE(out.judged);
  EXPECT_LT(out.first_raise, 0.0);
}

// The correlation does not scale with the supply; the step must not read as a leak.
TEST(DetailXcorrDetector, QuietAcrossASupplyStep) {
  auto detector = make_detector("detail_xcorr", kPressures, 0.04, nullptr);
  test::SyntheticPressures rig;
  rig.supply_step_at = 300.0;
  rig.supply_after = 14e6;
  const Outcome out = run(*detector, rig, 600.0);
  EXPECT_TRUE(out.judged);
  EXPECT_LT(out.first_raise, 0.0);
}

TEST(DetailXcorrDetector, GapsRestartTheFiltersAndJudgingResumes) {
  auto detector = make_detector("detail_xcorr", kPressures, 0.04, nullptr);
  test::SyntheticPressures rig;
  run(*detector, rig, 200.0);
  Observation o = rig.next();
  std::vector<double> with_gap(o.p1_samples.begin(), o.p1_samples.end());
  with_gap[5] = std::nan("");
  o.p1_samples = with_gap;
  EXPECT_FALSE(detector->update(o).learning);
  // The next 0.8 s refill the filters and the window; a block later it judges again.
  bool judged = false;
  for (int i = 0; i < 100; ++i) judged |= !std::isnan(detector->update(rig.next()).score);
  EXPECT_TRUE(judged);
}

TEST(DetailXcorrDetector, ImportedStateDecidesExactlyAsTheOriginal) {
  auto original = make_detector("detail_xcorr", kPressures, 0.04, nullptr);
  test::SyntheticPressures rig;
  rig.onset = 250.0;
  rig.leak_pole_radius = 0.96;
  run(*original, rig, 200.0);
  auto copy = make_detector("detail_xcorr", kPressures, 0.04, nullptr);
  copy->import_state(original->export_state());
  int compared = 0;
  while (rig.t < 300.0) {
    const Observation o = rig.next();
    const Decision a = original->update(o);
    const Decision b = copy->update(o);
    if (std::isnan(a.score)) {
      EXPECT_TRUE(std::isnan(b.score));
      continue;
    }
    EXPECT_EQ(a.score, b.score);
    ++compared;
  }
  EXPECT_GT(compared, 1000);
  auto index = make_detector("index_cusum", kPressures, 0.04, nullptr);
  EXPECT_THROW(index->import_state(original->export_state()), StateError);
}

}  // namespace
}  // namespace leakmon::detect
