// Tests hide an effect: each run draws, with fresh seeds (printed; LEAKMON_TEST_SEED forces
// one), one case per effect of the library plus a clean one: the effect's parameters within
// MODEL.md's ranges, the calibratable parameters within theirs, a controller and a reference.
// The simulator makes the noisy "measured" capture and the model check must name the effect
// and estimate its main parameter within 25 %.
//
// The workflow is a statistical decision: a weak effect drawn at the low end of its range
// (little entrained air, a small supply ripple) can stay below the significance threshold and
// be reported as `none`. So the per-run assertions are: the clean cases are clean (a per-run
// statistic over four, HiddenEffect.CleanDataGivesNone says why), no case is
// ever given a wrong cause, and at least 9 of the 11 effects are named with their main
// parameter within 25 % (`leakmon model evaluate` found 118 of 120: with that rate a run
// misses two of eleven about once in 70, three about once in 1200). The >= 95 % / >= 90 %
// targets are measured over many cases by `leakmon model evaluate` (docs/model-check.md).
#include <gtest/gtest.h>

#include <algorithm>
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

// Clean data over several fresh captures (seeds first, first + 1, ...; LEAKMON_TEST_SEED=first
// reproduces the run): `none` is a statistical decision, and one capture in about 25 named an
// effect before the smallest-instance rule (effect_library.hpp), so a single case cannot be
// asserted to be clean in every run. Asserted per run, with margins: at most one of four named
// (at a false-naming rate of 3 %, two or more of four happen in 0.5 % of runs; 0 of 126 clean
// captures were named in docs/model-check.md's evaluation), the nominal model at its noise
// floor in every case (`none` needs 1.3 x the floor; 1.6 x asserted), and the leading
// candidate's held-out evidence, median over the four, far below the naming threshold.
TEST(HiddenEffect, CleanDataGivesNone) {
  constexpr int kCases = 4;
  const std::uint64_t first = test::model_test_seed("HiddenEffect/clean (first of 4)");
  int named = 0;
  std::vector<double> leading_t;
  for (int k = 0; k < kCases; ++k) {
    const std::uint64_t seed = first + static_cast<std::uint64_t>(k);
    const SyntheticCase c = draw_case(seed, "none");
    const Diagnosis d = diagnose(measured_record(simulate_case(c)));
    double t = 0.0;
    std::string leading = "-";
    for (const auto& r : d.ranking) {
      if (!r.plausible || !r.refined) continue;
      t = r.significance;
      leading = r.effect;
      break;
    }
    std::printf("  clean seed %llu: %s, nrmse %.4f floor %.4f, leading %s t %.2f\n",
                static_cast<unsigned long long>(seed), d.cause.c_str(), d.nrmse_before,
                d.nrmse_floor, leading.c_str(), t);
    named += d.cause != "none";
    leading_t.push_back(t);
    EXPECT_LE(d.nrmse_before, 1.6 * d.nrmse_floor) << "seed " << seed;
    if (d.cause == "none") {
      EXPECT_DOUBLE_EQ(d.nrmse_after, d.nrmse_before) << "seed " << seed;
    }
  }
  EXPECT_LE(named, 1) << "clean captures given a cause, of " << kCases;
  std::sort(leading_t.begin(), leading_t.end());
  const double median_t = 0.5 * (leading_t[kCases / 2 - 1] + leading_t[kCases / 2]);
  EXPECT_LT(median_t, DiagnosisSettings{}.min_significance)
      << "median held-out evidence of the leading candidate on clean data";
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
