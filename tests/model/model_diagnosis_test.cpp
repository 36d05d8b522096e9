// Tests hide an effect: each run draws, with fresh seeds (printed; LEAKMON_TEST_SEED forces
// one), one case per effect of the library plus a clean one: the effect's parameters within
// MODEL.md's ranges, the calibratable parameters within theirs, a controller and a reference.
// The simulator makes the noisy "measured" capture and the model check must name the effect
// and estimate its main parameter within 25 %.
//
// The workflow is a statistical decision: a weak effect drawn at the low end of its range
// (little entrained air, a small supply ripple) can stay below the significance threshold and
// be reported as `none`. So the per-run assertions are: the clean case is clean, no case is
// ever given a wrong cause, and at least 9 of the 11 effects are named with their main
// parameter within 25 % (`leakmon model evaluate` found 118 of 120: with that rate a run
// misses two of eleven about once in 70, three about once in 1200). The >= 95 % / >= 90 %
// targets are measured over many cases by `leakmon model evaluate` (docs/model-check.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "model/diagnosis.hpp"
#include "model/evaluation.hpp"
#include "model/synthetic_case.hpp"
#include "tests/model/test_seed.hpp"

namespace leakmon::model {
namespace {

const std::vector<std::string> kEffects = {
    "internal_leakage", "external_leakage", "coulomb_friction", "entrained_air",
    "valve_overlap",    "valve_bias",       "spool_lag",        "supply_ripple",
    "supply_droop",     "sensor_offset",    "sensor_lag"};

struct Outcome {
  std::string truth, named;
  double true_value = 0, estimate = 0;
  bool parameter_ok = false;
  double nrmse_before = 0, nrmse_after = 0;
  std::uint64_t seed = 0;
};

Outcome run_case(const std::string& effect) {
  Outcome o;
  o.truth = effect;
  o.seed = test::model_test_seed(("HiddenEffect/" + effect).c_str());
  const SyntheticCase c = draw_case(o.seed, effect);
  const Diagnosis d = diagnose(measured_record(simulate_case(c)));
  o.named = d.cause;
  o.nrmse_before = d.nrmse_before;
  o.nrmse_after = d.nrmse_after;
  if (effect != "none" && d.cause == effect) {
    o.true_value = c.main_value;
    o.estimate = main_estimate(d, c.main_parameter);
    o.parameter_ok = std::abs(o.estimate - c.main_value) <= 0.25 * std::abs(c.main_value);
  }
  return o;
}

TEST(HiddenEffect, CleanDataGivesNone) {
  const Outcome o = run_case("none");
  EXPECT_EQ(o.named, "none") << "seed " << o.seed;
  EXPECT_DOUBLE_EQ(o.nrmse_after, o.nrmse_before);
}

TEST(HiddenEffect, EveryEffectOfTheLibraryIsFoundOrAtWorstMissed) {
  int found = 0;
  for (const auto& effect : kEffects) {
    const Outcome o = run_case(effect);
    std::printf("  %-17s -> %-17s param %s (true %.4g, estimate %.4g)  nrmse %.4f -> %.4f\n",
                o.truth.c_str(), o.named.c_str(), o.parameter_ok ? "ok " : "BAD", o.true_value,
                o.estimate, o.nrmse_before, o.nrmse_after);
    // A wrong cause sends the engineer after the wrong part: never acceptable. A miss is
    // `none`, or `unexplained` (issue 12) when the nominal model stays above the noise floor.
    EXPECT_TRUE(o.named == effect || o.named == "none" || o.named == "unexplained")
        << effect << " was named " << o.named << " (seed " << o.seed << ")";
    if (o.named == effect) {
      EXPECT_LT(o.nrmse_after, o.nrmse_before) << effect << " seed " << o.seed;
    }
    if (o.named == effect && o.parameter_ok) ++found;
  }
  EXPECT_GE(found, 9) << "named with the main parameter within 25 %: " << found << " of "
                      << kEffects.size();
}

}  // namespace
}  // namespace leakmon::model
