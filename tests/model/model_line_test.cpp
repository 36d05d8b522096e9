// The supply-ripple line test (model/spectral_line.hpp) on fresh random cases: the coherent
// second-half statistic must find a clear supply ripple at its frequency, stay well below
// the naming threshold on a clean capture, and use a capture's supply-pressure column when
// there is one. 30 s captures keep it cheap for the sanitizer builds (the statistic grows
// with the square root of the length; 60 s is typical).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "model/diagnosis.hpp"
#include "model/measured_record.hpp"
#include "model/spectral_line.hpp"
#include "model/synthetic_case.hpp"
#include "sim/rig_draw.hpp"
#include "tests/model/test_seed.hpp"

namespace leakmon::model {
namespace {

constexpr double kDuration = 30.0;

TEST(SpectralLine, FindsARippleAtItsFrequency) {
  const auto seed = test::model_test_seed("SpectralLine.FindsARippleAtItsFrequency");
  // 60 s, not 30: at 30 s one draw in about 30 left a clear 8e5 Pa ripple at z 4.1-4.5, just
  // under the naming threshold (the statistic grows with the root of the length).
  SyntheticCase c = draw_case(seed, "supply_ripple", {2.0 * kDuration});
  c.scenario.effects.supply_ripple->dP = 8e5;  // MODEL.md: 2e5 .. 1e6
  const MeasuredRecord record = measured_record(simulate_case(c));
  const auto line = find_spectral_line(record);
  ASSERT_TRUE(line.has_value());
  const double f = c.scenario.effects.supply_ripple->f;
  std::printf("  ripple %.3f Hz: line at %.4f Hz, z %.2f\n", f, line->frequency_hz,
              line->held_out_z);
  EXPECT_NEAR(line->frequency_hz, f, 2e-3);
  EXPECT_GE(line->held_out_z, DiagnosisSettings{}.min_line_z);
  EXPECT_FALSE(line->from_supply_column);
}

TEST(SpectralLine, CleanCaptureHasNoSignificantLine) {
  const auto seed = test::model_test_seed("SpectralLine.CleanCaptureHasNoSignificantLine");
  for (std::uint64_t i = 0; i < 2; ++i) {
    const SyntheticCase c = draw_case(seed + i, "none", {kDuration});
    const auto line = find_spectral_line(measured_record(simulate_case(c)));
    ASSERT_TRUE(line.has_value());
    const double mode_hz = sim::hydraulic_mode_hz(c.scenario.params);
    std::printf("  clean seed %llu: tallest line %.3f Hz, z %.2f (the rig's mode %.1f Hz)\n",
                static_cast<unsigned long long>(seed + i), line->frequency_hz, line->held_out_z,
                mode_hz);
    // Without a line each of the 8 candidates is N(0, 1): 4.5 is far out (and the naming
    // threshold); the largest of 8 passes it about once in 37000 captures. The rig's own
    // hydraulic mode, rung by the spool's flow noise, is no such candidate: CI's fresh seed
    // 12352942346923629451 had its tallest line at 85.2 Hz, near the mode, at z 4.5009
    // (docs/model-check.md: lines at the mode pass the line test; a ripple is still named only
    // as a forward step that gains). Within 25 % of the mode the line is reported, not held.
    if (std::abs(line->frequency_hz / mode_hz - 1.0) > 0.25) {
      EXPECT_LT(line->held_out_z, DiagnosisSettings{}.min_line_z);
    }
  }
}

TEST(SpectralLine, UsesTheSupplyPressureColumnWhenPresent) {
  const auto seed = test::model_test_seed("SpectralLine.UsesTheSupplyPressureColumnWhenPresent");
  const SyntheticCase c = draw_case(seed, "none", {kDuration});
  capture::Capture capture = simulate_case(c);
  // A supply transducer reading a 2e5 Pa, 47.3 Hz ripple with the chamber transducers' noise;
  // the chambers themselves carry none (a ripple upstream of a filter, say).
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> noise(0.0, 5e3);
  std::vector<double> ps;
  for (double t : capture.column("t")) {
    ps.push_back(17.2e6 + 2e5 * std::sin(2.0 * std::numbers::pi * 47.3 * t) + noise(engine));
  }
  capture.columns.push_back("ps");
  capture.values.push_back(ps);
  const auto line = find_spectral_line(measured_record(capture));
  ASSERT_TRUE(line.has_value());
  EXPECT_TRUE(line->from_supply_column);
  EXPECT_NEAR(line->frequency_hz, 47.3, 1e-3);
  EXPECT_GE(line->held_out_z, 20.0);
}

}  // namespace
}  // namespace leakmon::model
