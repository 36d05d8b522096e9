// Monte-Carlo evaluation of the model check (`leakmon model evaluate`): cases drawn afresh
// from MODEL.md (synthetic_case.hpp), each diagnosed, tallied into naming accuracy, parameter
// accuracy, NRMSE gain and the confusion matrix of docs/model-check.md.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/diagnosis.hpp"
#include "model/synthetic_case.hpp"

namespace leakmon::model {

struct CaseOutcome {
  std::uint64_t seed = 0;
  std::string truth, named;
  std::string main_parameter;
  double true_value = 0.0, estimate = 0.0;  // main parameter; estimate 0 when not named
  double nrmse_before = 0.0, nrmse_after = 0.0;
  double seconds = 0.0;  // diagnosis wall time
  // The best plausible refined extension, named or not, and its held-out evidence: the
  // margins to the naming thresholds (DiagnosisSettings) over many cases.
  std::string leading;
  double leading_score = 0.0, leading_significance = 0.0;
  double line_z = 0.0;  // the supply-ripple line test's statistic
  bool named_correctly() const { return truth == named; }
  bool parameter_within(double tolerance) const;
};

// Case i uses seed `first_seed + i` and cycles through the eleven effects and none, so that
// every effect is drawn equally often.
CaseOutcome evaluate_case(std::uint64_t seed, const std::string& effect,
                          const CaseSettings& case_settings = {},
                          const DiagnosisSettings& settings = {});

struct EvaluationSummary {
  std::vector<CaseOutcome> cases;
  std::string markdown() const;  // accuracy figures and the confusion matrix
  std::string csv() const;       // one line per case
};

// The main parameter's estimate in a diagnosis (0 when the cause differs from `effect`).
double main_estimate(const Diagnosis& d, const std::string& main_parameter);

}  // namespace leakmon::model
