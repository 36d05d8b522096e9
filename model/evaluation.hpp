// Monte-Carlo evaluation of the model check (`leakmon model evaluate`): cases drawn afresh
// from MODEL.md (synthetic_case.hpp), each diagnosed, tallied into naming accuracy, parameter
// accuracy, NRMSE gain and the confusion matrix of docs/model-check.md.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "model/diagnosis.hpp"
#include "model/synthetic_case.hpp"

namespace leakmon::model {

struct CaseOutcome {
  std::uint64_t seed = 0;
  std::string kind = "library";    // the evaluation class (case_kinds())
  std::vector<TrueEffect> truths;  // every effect present
  std::vector<std::string> named_causes;
  double visc_estimate = 0.0;  // oil_temperature's visc_slope when named
  // The generator's true model on the same held-out segments: the best any extension can do.
  // achieved = (before - after) / (before - true), the share of the achievable improvement.
  double nrmse_true = 0.0;
  double achieved = 0.0;
  std::string truth, named;
  std::string main_parameter;
  double true_value = 0.0, estimate = 0.0;  // main parameter; estimate 0 when not named
  double nrmse_before = 0.0, nrmse_after = 0.0;
  double seconds = 0.0;  // diagnosis wall time
  // The best plausible refined extension, named or not, and its held-out evidence: the
  // margins to the naming thresholds (DiagnosisSettings) over many cases.
  std::string leading;
  double leading_score = 0.0, leading_significance = 0.0;
  double line_z = 0.0;       // the supply-ripple line test's statistic
  double nrmse_floor = 0.0;  // the noise floor the diagnosis estimated
  std::string causes;        // every named effect, joined by '+' (empty: none named)
  bool drifts = false;
  std::string steps;     // forward selection: effect:score/t per step, ';'-separated
  std::string at_bound;  // calibrated values on a bound, joined by '+'
  // Other rigs (issue 24): the rig (a few of its values, for the CSV), the value stated wrong
  // and what the rig check found, the true onset and the one named with the true effect.
  std::string rig;
  std::string misstated;
  double misstated_true = 0.0, misstated_stated = 0.0;
  std::vector<RigFinding> rig_findings;
  double onset_true = 0.0, onset_estimate = 0.0;
  double onset_earliest = 0.0, onset_latest = 0.0;  // the stretch the data allow
  std::string program;  // the test program's phases in MODEL.md's notation, ';'-separated
  bool named_correctly() const { return truth == named; }
  // Exactly the true effects named: nothing else, no rig_parameter either.
  bool only_truth_named() const;
  // The mis-stated value named rig_parameter with its fitted value within `tolerance` of the
  // truth, and nothing else (no library effect, no other stated value).
  bool misstatement_found(double tolerance) const;
  double fitted_misstated() const;  // the rig check's value for `misstated`, NaN when not found
  bool parameter_within(double tolerance) const;
};

// Case i uses seed `first_seed + i` and cycles through the eleven effects and none, so that
// every effect is drawn equally often.
CaseOutcome evaluate_case(std::uint64_t seed, const std::string& effect,
                          const CaseSettings& case_settings = {},
                          const DiagnosisSettings& settings = {});

// The evaluation classes of issue 12: "library" (the eleven effects and none in turn),
// "pair" (two visible effects), "warmup_temp" / "warmup_no_temp" (the oil warming up, with and
// without the `temp` column), "edge" / "beyond" (an effect at / 1.5 times beyond its range's
// ends), "clean"; and of issue 24: "misstated" (no effect, one stated value wrong, the keys of
// misstatements() in turn), "onset" (one effect of onset_effects() appearing inside the
// capture). `--rigs other` draws every class on other rigs (CaseSettings::other_rig).
const std::vector<std::string>& case_kinds();
// The effects the "onset" class makes appear inside a capture: those whose appearance changes
// the signals beyond the noise (not entrained air and ripple, which are at the noise level even
// when present throughout, nor the oil, which warms gradually).
const std::vector<std::string>& onset_effects();
// The n-th case of a class: its effect string and settings.
std::pair<std::string, CaseSettings> case_of_kind(const std::string& kind, std::size_t n,
                                                  CaseSettings base);

struct EvaluationSummary {
  std::vector<CaseOutcome> cases;
  std::string markdown() const;       // accuracy figures and the confusion matrix
  std::string kind_markdown() const;  // issue 12's classes, one line each
  // Issue 12's targets one by one (a line each), with counts, over the classes drawn.
  std::string targets_markdown() const;
  std::string csv() const;  // one line per case
};

// The main parameter's estimate in a diagnosis (0 when the cause differs from `effect`).
double main_estimate(const Diagnosis& d, const std::string& main_parameter);

}  // namespace leakmon::model
