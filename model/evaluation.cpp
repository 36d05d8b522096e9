#include "model/evaluation.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <map>

#include "model/effect_library.hpp"

namespace leakmon::model {

bool CaseOutcome::parameter_within(double tolerance) const {
  if (truth == "none") return named == "none";
  if (named != truth || true_value == 0.0) return false;
  return std::abs(estimate - true_value) <= tolerance * std::abs(true_value);
}

double main_estimate(const Diagnosis& d, const std::string& main_parameter) {
  for (const auto& p : d.params) {
    if (p.name == main_parameter) return p.value;
  }
  return 0.0;
}

CaseOutcome evaluate_case(std::uint64_t seed, const std::string& effect,
                          const CaseSettings& case_settings, const DiagnosisSettings& settings) {
  const SyntheticCase c = draw_case(seed, effect, case_settings);
  const MeasuredRecord record = measured_record(simulate_case(c));
  const auto start = std::chrono::steady_clock::now();
  const Diagnosis d = diagnose(record, settings);
  CaseOutcome out;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.seed = seed;
  out.truth = c.effect;
  out.named = d.cause;
  out.main_parameter = c.main_parameter;
  out.true_value = c.main_value;
  out.estimate = main_estimate(d, c.main_parameter);
  out.nrmse_before = d.nrmse_before;
  out.nrmse_after = d.nrmse_after;
  for (const auto& r : d.ranking) {
    if (!r.plausible || !r.refined) continue;
    out.leading = r.effect;
    out.leading_score = r.score;
    out.leading_significance = r.significance;
    break;
  }
  if (d.ripple_line) out.line_z = d.ripple_line->held_out_z;
  return out;
}

std::string EvaluationSummary::csv() const {
  std::string out =
      "seed,truth,named,main_parameter,true_value,estimate,nrmse_before,"
      "nrmse_after,seconds,leading,leading_score,leading_significance,line_z\n";
  for (const auto& c : cases) {
    out += fmt::format("{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.3f},{},{:.5f},{:.3f},{:.3f}\n",
                       c.seed, c.truth, c.named, c.main_parameter, c.true_value, c.estimate,
                       c.nrmse_before, c.nrmse_after, c.seconds, c.leading, c.leading_score,
                       c.leading_significance, c.line_z);
  }
  return out;
}

std::string EvaluationSummary::markdown() const {
  std::vector<std::string> labels = effect_names();
  labels.push_back("none");
  std::map<std::string, std::map<std::string, int>> confusion;
  int named_ok = 0, param_ok = 0, halved = 0, named_causes = 0;
  double slowest = 0.0;
  for (const auto& c : cases) {
    ++confusion[c.truth][c.named];
    named_ok += c.named_correctly();
    param_ok += c.parameter_within(0.25);
    if (c.named != "none") {
      ++named_causes;
      halved += c.nrmse_after <= 0.5 * c.nrmse_before;
    }
    slowest = std::max(slowest, c.seconds);
  }
  const auto pct = [](int a, std::size_t b) {
    return b ? 100.0 * a / static_cast<double>(b) : 0.0;
  };
  std::string out;
  out += fmt::format(
      "| cases | cause named correctly | main parameter within 25 % (none: "
      "named none) | held-out NRMSE halved when a cause is named | slowest "
      "diagnosis |\n|---|---|---|---|---|\n");
  out += fmt::format("| {} | {:.1f} % | {:.1f} % | {:.1f} % ({} of {}) | {:.2f} s |\n\n",
                     cases.size(), pct(named_ok, cases.size()), pct(param_ok, cases.size()),
                     pct(halved, static_cast<std::size_t>(named_causes)), halved, named_causes,
                     slowest);
  out += "Confusion matrix (rows: true effect, columns: named cause)\n\n| true \\ named |";
  for (const auto& l : labels) out += fmt::format(" {} |", l);
  out += "\n|---|";
  for (std::size_t i = 0; i < labels.size(); ++i) out += "---|";
  out += "\n";
  for (const auto& t : labels) {
    out += fmt::format("| {} |", t);
    for (const auto& n : labels) {
      const int k = confusion[t][n];
      out += k ? fmt::format(" {} |", k) : " . |";
    }
    out += "\n";
  }
  return out;
}

}  // namespace leakmon::model
