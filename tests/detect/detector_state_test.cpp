// Detector export/import (detector_state.hpp): the text form round-trips every double exactly,
// and a detector restored at any point of its run (learning, judging, alarm building) decides
// exactly as the one that never stopped.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "detect/detector_state.hpp"
#include "detect/factory.hpp"
#include "tests/detect/synthetic_rig.hpp"

namespace leakmon::detect {
namespace {

constexpr AvailableSignals kAll{true, true, true, true};
constexpr AvailableSignals kPressuresOnly{true, true, false, false};

bool same(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

AvailableSignals signals_for(const std::string& kind) {
  return kind == "flow_balance" || kind == "fused" ? kAll : kPressuresOnly;
}

TEST(DetectorState, TextRoundTripIsExact) {
  DetectorState state("probe", 3);
  const double tricky[] = {0.1,
                           1.0 / 3.0,
                           -0.0,
                           5e-324,
                           std::numeric_limits<double>::max(),
                           std::numeric_limits<double>::quiet_NaN(),
                           -std::numeric_limits<double>::infinity(),
                           2.5e-13 * 17.2e6};
  state.put("values", tricky);
  state.put("empty", std::span<const double>{});
  state.put_count("count", 123456789012345);
  DetectorState member("inner", 1);
  member.put("x", 0.7);
  state.put_nested("m0", member);
  const DetectorState back = DetectorState::parse(state.text());
  EXPECT_TRUE(back == state) << state.text();
  const auto& values = back.get_list("values");
  ASSERT_EQ(values.size(), std::size(tricky));
  for (std::size_t i = 0; i < values.size(); ++i) EXPECT_TRUE(same(values[i], tricky[i])) << i;
  EXPECT_EQ(back.get_count("count"), 123456789012345u);
  EXPECT_TRUE(back.get_nested("m0") == member);
}

TEST(DetectorState, MalformedTextAndMisfitsThrow) {
  EXPECT_THROW(DetectorState::parse("kind paper\nversion 1\nx 1.0 abc\n"), StateError);
  EXPECT_THROW(DetectorState::parse("x 1.0\n"), StateError);
  EXPECT_THROW(DetectorState::parse("kind a\nversion 1\nx 1\nx 2\n"), StateError);
  auto flow = make_detector("flow_balance", kAll, 0.04, nullptr);
  auto index = make_detector("index_cusum", kAll, 0.04, nullptr);
  EXPECT_THROW(index->import_state(flow->export_state()), StateError);
  DetectorState newer("flow_balance", 99);
  EXPECT_THROW(flow->import_state(newer), StateError);
  // A judging window of another length (other options) does not fit.
  auto paper = make_detector("paper", kPressuresOnly, 0.04, nullptr);
  auto other_paper = make_detector("paper", kPressuresOnly, 0.02, nullptr);
  EXPECT_THROW(other_paper->import_state(paper->export_state()), StateError);
}

struct Restart {
  std::string kind;
  double cut_seconds;  // when the state is taken: while learning, judging, or in the leak
};

class DetectorRestart : public ::testing::TestWithParam<Restart> {};

// The leak opens at 150 s, after learning (92 s). The restored detector (state through text)
// and the one that never stopped see the same following observations and must agree exactly.
TEST_P(DetectorRestart, RestoredDetectorDecidesAsTheOneThatNeverStopped) {
  const auto& [kind, cut] = GetParam();
  auto running = make_detector(kind, signals_for(kind), 0.04, nullptr);
  test::SyntheticRig rig;
  rig.onset = 150.0;
  rig.leak = 2e-12;
  rig.index_drop = 0.5;
  while (rig.t < cut) running->update(rig.next());

  const DetectorState saved = running->export_state();
  const DetectorState through_text = DetectorState::parse(saved.text());
  ASSERT_TRUE(through_text == saved);
  auto restored = make_detector(kind, signals_for(kind), 0.04, nullptr);
  restored->import_state(through_text);
  EXPECT_TRUE(restored->export_state() == saved);
  // What the daemon did before this change: relearn from the restart on.
  auto relearning = make_detector(kind, signals_for(kind), 0.04, nullptr);

  std::size_t compared = 0, raised = 0, relearning_raised = 0;
  while (rig.t < 400.0) {
    const Observation o = rig.next();
    const Decision a = running->update(o);
    const Decision b = restored->update(o);
    const Decision c = relearning->update(o);
    ASSERT_TRUE(same(a.score, b.score)) << o.t << ": " << a.score << " vs " << b.score;
    ASSERT_EQ(a.learning, b.learning) << o.t;
    ASSERT_TRUE(same(a.baseline, b.baseline)) << o.t;
    ASSERT_TRUE(same(a.index, b.index)) << o.t;
    ASSERT_TRUE(same(a.leak_coefficient, b.leak_coefficient)) << o.t;
    ASSERT_TRUE(same(a.leak_coefficient_ci, b.leak_coefficient_ci)) << o.t;
    ASSERT_EQ(a.judged, b.judged) << o.t;
    ASSERT_EQ(a.not_judged_reason, b.not_judged_reason) << o.t;
    ++compared;
    if (b.score >= restored->raise_threshold()) ++raised;
    if (c.score >= relearning->raise_threshold()) ++relearning_raised;
  }
  EXPECT_GT(compared, 5000u);
  // The comparison covered an alarm: the leak was found by the restored detector.
  EXPECT_GT(raised, 0u) << kind;
  // Restarted inside the leak, a detector that relearns takes the leak for healthy.
  if (cut > 150.0) {
    EXPECT_EQ(relearning_raised, 0u) << kind;
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryKind, DetectorRestart,
    ::testing::Values(Restart{"paper", 40.0}, Restart{"paper", 120.0}, Restart{"paper", 170.0},
                      Restart{"index_cusum", 40.0}, Restart{"index_cusum", 120.0},
                      Restart{"index_cusum", 170.0}, Restart{"flow_balance", 40.0},
                      Restart{"flow_balance", 120.0}, Restart{"flow_balance", 151.3},
                      Restart{"fused", 40.0}, Restart{"fused", 120.0}, Restart{"fused", 170.0}),
    [](const auto& param_info) {
      return param_info.param.kind + "_at_" +
             std::to_string(static_cast<int>(param_info.param.cut_seconds));
    });

}  // namespace
}  // namespace leakmon::detect
