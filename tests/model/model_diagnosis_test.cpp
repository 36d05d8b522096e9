// Tests hide an effect: each case draws, with a fresh seed (printed; LEAKMON_TEST_SEED forces
// one), the effect's parameters within MODEL.md's ranges, the calibratable parameters within
// theirs, a controller and a reference; the simulator makes the noisy "measured" capture and
// the model check must name the effect and estimate its main parameter within 25 %.
#include <gtest/gtest.h>

#include <string>

#include "model/diagnosis.hpp"
#include "model/evaluation.hpp"
#include "model/synthetic_case.hpp"
#include "tests/model/test_seed.hpp"

namespace leakmon::model {
namespace {

class HiddenEffect : public testing::TestWithParam<std::string> {};

TEST_P(HiddenEffect, IsNamedWithItsMainParameter) {
  const std::string effect = GetParam();
  const auto seed = test::model_test_seed(("HiddenEffect/" + effect).c_str());
  const SyntheticCase c = draw_case(seed, effect);
  const MeasuredRecord record = measured_record(simulate_case(c));
  const Diagnosis d = diagnose(record);
  ASSERT_EQ(d.cause, effect) << "seed " << seed << ", true " << c.main_parameter << " = "
                             << c.main_value;
  if (effect == "none") {
    EXPECT_TRUE(d.params.empty());
    EXPECT_DOUBLE_EQ(d.nrmse_after, d.nrmse_before);
    return;
  }
  const double estimate = main_estimate(d, c.main_parameter);
  EXPECT_NEAR(estimate, c.main_value, 0.25 * std::abs(c.main_value))
      << "seed " << seed << ", " << c.main_parameter;
  EXPECT_LT(d.nrmse_after, d.nrmse_before);
}

INSTANTIATE_TEST_SUITE_P(ModelCheck, HiddenEffect,
                         testing::Values("none", "internal_leakage", "external_leakage",
                                         "coulomb_friction", "entrained_air", "valve_overlap",
                                         "valve_bias", "spool_lag", "supply_ripple", "supply_droop",
                                         "sensor_offset", "sensor_lag"));

}  // namespace
}  // namespace leakmon::model
