// Multi-minute closed-loop runs (label `long`): both controllers, healthy and with the largest
// leak of MODEL.md's range, stay bounded and keep tracking over 30 minutes of random steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sim/rig.hpp"
#include "sim/scenario.hpp"

namespace leakmon::sim {
namespace {

class LongStability : public ::testing::TestWithParam<std::tuple<ControllerKind, double>> {};

TEST_P(LongStability, ThirtyMinutesOfRandomStepsStayBoundedAndTracked) {
  const auto [kind, C_L] = GetParam();
  Scenario s = preset(kind == ControllerKind::basic ? "healthy" : "healthy-ft", 99);
  s.duration_s = 1800.0;
  if (C_L > 0.0) s.effects.internal_leakage = InternalLeakage{C_L, 60.0, 0.0};
  Rig rig(s);
  double worst_x = 0.0, square_error_last_minute = 0.0;
  std::uint64_t n = s.samples(), last_minute = 0;
  for (std::uint64_t k = 0; k < n; ++k) {
    const RigSample r = rig.step();
    ASSERT_TRUE(std::isfinite(r.p1_true) && std::isfinite(r.x_true)) << "t=" << r.t;
    worst_x = std::max(worst_x, std::abs(r.x_true));
    if (k + 30000 >= n) {
      square_error_last_minute += (r.x_true - r.xref) * (r.x_true - r.xref);
      ++last_minute;
    }
  }
  EXPECT_LT(worst_x, 0.06);
  EXPECT_LT(std::sqrt(square_error_last_minute / last_minute), 0.012);
}

INSTANTIATE_TEST_SUITE_P(Controllers, LongStability,
                         ::testing::Combine(::testing::Values(ControllerKind::basic,
                                                              ControllerKind::fault_tolerant),
                                            ::testing::Values(0.0, 5e-12)));

}  // namespace
}  // namespace leakmon::sim
