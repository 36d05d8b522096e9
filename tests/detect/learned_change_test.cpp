// The learned-change probes on synthetic learning periods (detect/learned_change.hpp): a step of
// alarm-worthy size after the reference share is found at its block; noise, a step too small to
// matter, a step inside the reference share and a step that does not stay are not.
#include "detect/learned_change.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <span>
#include <vector>

namespace leakmon::detect {
namespace {

// 100 blocks of 1 s, leak term alternating in sign and size like holds under both loads, a
// residual of spread 1 plus `slope` times the leak term from `onset` on.
std::vector<ResidualBlock> residual_blocks(double slope, double onset, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<ResidualBlock> blocks;
  for (int i = 0; i < 100; ++i) {
    const double t = static_cast<double>(i);
    const double leak_term = (i % 2 == 0 ? 1.0 : -0.6) * (1.0 + 0.3 * (i % 5));
    blocks.push_back(
        {t, t + 0.9, noise(generator) + (t >= onset ? slope * leak_term : 0.0), leak_term});
  }
  return blocks;
}

SlopeStepOptions slope_options() {
  SlopeStepOptions options;
  options.floor_slope = 1.0;
  options.slope_to_coefficient = 2.0;
  return options;
}

TEST(SlopeStep, AStepAfterTheReferenceIsFoundAtItsBlock) {
  const auto blocks = residual_blocks(3.0, 70.0, 1);
  const auto change = find_slope_step(blocks, 40, slope_options());
  ASSERT_TRUE(change.has_value());
  EXPECT_NEAR(change->change_t, 70.0, 2.0);
  EXPECT_NEAR(change->size, 6.0, 1.5);  // the slope 3 times slope_to_coefficient
  EXPECT_EQ(change->channel, "u");
}

TEST(SlopeStep, NoiseAndASmallStepAreNot) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    EXPECT_FALSE(find_slope_step(residual_blocks(0.0, 0.0, seed), 40, slope_options()));
  }
  // Significant (hundreds of blocks would show it) but below the floor.
  SlopeStepOptions options = slope_options();
  options.floor_slope = 4.0;
  EXPECT_FALSE(find_slope_step(residual_blocks(3.0, 70.0, 1), 40, options));
}

TEST(SlopeStep, TooLittleDataIsNoVerdict) {
  const auto blocks = residual_blocks(3.0, 70.0, 1);
  EXPECT_FALSE(find_slope_step({blocks.data(), 2}, 2, slope_options()));
  EXPECT_FALSE(find_slope_step({blocks.data(), 42}, 40, slope_options()));
}

// A reference of 6 blocks fitted with 6 terms leaves residuals near zero whatever the noise (a
// 12 s learning period on a healthy rig with gaps: a step of 70 standard errors). The fitted
// terms take their degrees of freedom from the spread; too few left is no verdict.
TEST(SlopeStep, AReferenceFittedAlmostExactlyIsNoVerdict) {
  // A reference fitted to 1e-3 of the noise, and the fit extrapolated to the next loads, off by
  // a slope as large as a leak's.
  auto blocks = residual_blocks(1.5, 6.0, 4);
  for (std::size_t i = 0; i < 6; ++i) blocks[i].residual *= 1e-3;
  SlopeStepOptions options = slope_options();
  std::span<const ResidualBlock> short_period(blocks.data(), 16);
  const auto noise_as_step = find_slope_step(short_period, 6, options);  // the fit's terms ignored
  ASSERT_TRUE(noise_as_step.has_value());
  EXPECT_GT(noise_as_step->z, 50.0);
  options.fitted_terms = 6;
  EXPECT_FALSE(find_slope_step(short_period, 6, options).has_value());
  // With enough reference blocks the fitted terms cost a little spread, and a real step shows.
  const auto stepped = residual_blocks(3.0, 70.0, 1);
  EXPECT_TRUE(find_slope_step(stepped, 40, options).has_value());
  for (unsigned seed = 1; seed <= 20; ++seed) {
    EXPECT_FALSE(find_slope_step(residual_blocks(0.0, 0.0, seed), 40, options));
  }
}

// 90 s of learning at 10 hops a second, an index of 20 kPa with hop noise and a slow wobble.
void feed(IndexStepProbe& probe, double drop, double onset, double until, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> noise(0.0, 1500.0);
  for (int hop = 0; hop < 900; ++hop) {
    const double t = 0.1 * hop;
    const double level = 20e3 + 600.0 * std::sin(t / 9.0) - (t >= onset && t < until ? drop : 0.0);
    probe.add(t, level + noise(generator));
  }
}

TEST(IndexStep, ADropAfterTheReferenceIsFoundNearItsOnset) {
  IndexStepProbe probe("p2", 90.0, 0.1);
  feed(probe, 8e3, 62.0, 1e9, 3);
  const auto change = probe.judge();
  ASSERT_TRUE(change.has_value());
  EXPECT_EQ(change->channel, "p2");
  EXPECT_EQ(change->feature, "index");
  EXPECT_NEAR(change->change_t, 62.0, 4.0);
  EXPECT_NEAR(change->size, 8e3, 1.5e3);
  EXPECT_NEAR(change->reference, 20e3, 1.5e3);
}

TEST(IndexStep, WobbleASmallDropAndADropThatDoesNotStayAreNot) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    IndexStepProbe probe("p1", 90.0, 0.1);
    feed(probe, 0.0, 0.0, 0.0, seed);
    EXPECT_FALSE(probe.judge()) << seed;
  }
  IndexStepProbe small("p1", 90.0, 0.1);
  feed(small, 3e3, 62.0, 1e9, 3);  // 15 %: within what drift does
  EXPECT_FALSE(small.judge());
  IndexStepProbe passing("p1", 90.0, 0.1);
  feed(passing, 8e3, 50.0, 60.0, 3);  // back after 10 s
  EXPECT_FALSE(passing.judge());
  // Cleared: forgets the drop.
  IndexStepProbe cleared("p1", 90.0, 0.1);
  feed(cleared, 8e3, 62.0, 1e9, 3);
  cleared.clear();
  feed(cleared, 0.0, 0.0, 0.0, 4);
  EXPECT_FALSE(cleared.judge());
}

}  // namespace
}  // namespace leakmon::detect
