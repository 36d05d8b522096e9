#include "model/evaluation.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>

#include "model/effect_library.hpp"

namespace leakmon::model {

bool CaseOutcome::parameter_within(double tolerance) const {
  if (truth == "none") return named == "none";
  if (named != truth || true_value == 0.0) return false;
  return std::abs(estimate - true_value) <= tolerance * std::abs(true_value);
}

bool CaseOutcome::only_truth_named() const {
  if (named_causes.size() != truths.size()) return false;
  return std::all_of(truths.begin(), truths.end(), [&](const TrueEffect& t) {
    return std::find(named_causes.begin(), named_causes.end(), t.effect) != named_causes.end();
  });
}

double CaseOutcome::fitted_misstated() const {
  for (const auto& f : rig_findings) {
    if (f.parameter == misstated) return f.fitted;
  }
  return std::nan("");
}

bool CaseOutcome::misstatement_found(double tolerance) const {
  if (misstated.empty() || rig_findings.size() != 1) return false;
  const auto& f = rig_findings.front();
  const bool only_rig = std::all_of(named_causes.begin(), named_causes.end(),
                                    [](const std::string& n) { return n == "rig_parameter"; });
  return only_rig && f.parameter == misstated &&
         std::abs(f.fitted - misstated_true) <= tolerance * std::abs(misstated_true);
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
  const Diagnosis d = diagnose(record, c.told, settings);
  CaseOutcome out;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.seed = seed;
  out.truth = c.effect;
  out.named = d.cause;
  out.main_parameter = c.main_parameter;
  out.true_value = c.main_value;
  // The main parameter of the true effect's cause (the first cause may be a rig_parameter).
  out.estimate = main_estimate(d, c.main_parameter);
  for (const auto& cause : d.causes) {
    if (!c.effects.empty() && cause.effect == c.effects.front().effect) {
      for (const auto& p : cause.params) {
        if (p.name == c.main_parameter) out.estimate = p.value;
      }
      out.onset_estimate = cause.onset_s;
      out.onset_earliest = cause.onset_earliest_s;
      out.onset_latest = cause.onset_latest_s;
    }
  }
  const auto& rig = c.scenario.params;
  out.rig = fmt::format("D={:.0f}mm ps={:.1f}MPa K_s={:.0f}kN/m m={:.3g}kg Kv={:.3g} tau={:.3g}ms",
                        rig.D * 1e3, rig.ps * 1e-6, rig.K_s * 1e-3, rig.m, rig.Kv, rig.tau * 1e3);
  for (const auto& phase : c.scenario.program) {
    out.program += fmt::format("{}{} {:.0f}s", out.program.empty() ? "" : ";", phase.notation(),
                               phase.duration_s);
  }
  out.misstated = c.misstated;
  out.misstated_true = c.misstated_true;
  out.misstated_stated = c.misstated_stated;
  out.rig_findings = d.rig_check.findings;
  out.onset_true = c.onset_s;
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
  out.nrmse_floor = d.nrmse_floor;
  out.truths = c.effects;
  for (const auto& cause : d.causes) {
    out.named_causes.push_back(cause.effect);
    if (cause.effect == "oil_temperature") {
      for (const auto& p : cause.params) {
        if (p.name == "visc_slope") out.visc_estimate = p.value;
      }
    }
  }
  const SegmentPredictor predictor(record, c.scenario.params);  // the true rig
  out.nrmse_true = predictor.nrmse(true_model(c), d.held_out_used);
  const double achievable = out.nrmse_before - out.nrmse_true;
  out.achieved = achievable > 0.0 ? (out.nrmse_before - out.nrmse_after) / achievable : 1.0;
  for (const auto& cause : d.causes) out.causes += (out.causes.empty() ? "" : "+") + cause.effect;
  out.drifts = d.drifts || (d.unexplained && d.unexplained->drifts);
  for (const auto& s : d.steps) {
    out.steps += fmt::format("{}{}{}:{:.3f}/{:.1f}{}", out.steps.empty() ? "" : ";", s.effect,
                             s.replaces.empty() ? "" : "<-" + s.replaces, s.score, s.significance,
                             s.accepted ? "" : "(rejected)");
  }
  for (const auto& name : d.at_bound) out.at_bound += (out.at_bound.empty() ? "" : "+") + name;
  return out;
}

std::string EvaluationSummary::csv() const {
  std::string out =
      "seed,truth,named,main_parameter,true_value,estimate,nrmse_before,"
      "nrmse_after,seconds,leading,leading_score,leading_significance,line_z,nrmse_floor,"
      "causes,drifts,at_bound,steps,kind,nrmse_true,achieved,visc_estimate,rig,misstated,"
      "misstated_true,misstated_stated,rig_findings,onset_true,onset_estimate,program,onset_"
      "earliest,onset_latest\n";
  for (const auto& c : cases) {
    std::string findings;
    for (const auto& f : c.rig_findings) {
      findings += fmt::format("{}{}:{:.6g}", findings.empty() ? "" : "+", f.parameter, f.fitted);
    }
    out += fmt::format(
        "{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.3f},{},{:.5f},{:.3f},{:.3f},{:.6g},{},{},{},{},"
        "{},{:.6g},{:.4f},{:.6g},{},{},{:.6g},{:.6g},{},{:.3f},{:.3f},{},{:.3f},{:.3f}\n",
        c.seed, c.truth, c.named, c.main_parameter, c.true_value, c.estimate, c.nrmse_before,
        c.nrmse_after, c.seconds, c.leading, c.leading_score, c.leading_significance, c.line_z,
        c.nrmse_floor, c.causes, c.drifts ? 1 : 0, c.at_bound, c.steps, c.kind, c.nrmse_true,
        c.achieved, c.visc_estimate, c.rig, c.misstated, c.misstated_true, c.misstated_stated,
        findings, c.onset_true, c.onset_estimate, c.program, c.onset_earliest, c.onset_latest);
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

const std::vector<std::string>& case_kinds() {
  static const std::vector<std::string> kinds = {"library",        "pair",      "warmup_temp",
                                                 "warmup_no_temp", "edge",      "beyond",
                                                 "clean",          "misstated", "onset"};
  return kinds;
}

const std::vector<std::string>& onset_effects() {
  static const std::vector<std::string> effects = {
      "internal_leakage", "external_leakage", "coulomb_friction", "valve_overlap", "valve_bias",
      "spool_lag",        "supply_droop",     "sensor_offset",    "sensor_lag"};
  return effects;
}

std::pair<std::string, CaseSettings> case_of_kind(const std::string& kind, std::size_t n,
                                                  CaseSettings base) {
  // Pairs of effects that each show clearly on their own (issue 12's two examples first).
  static const std::vector<std::string> pairs = {"sensor_lag+spool_lag",
                                                 "sensor_lag+valve_overlap",
                                                 "internal_leakage+coulomb_friction",
                                                 "valve_bias+supply_droop",
                                                 "external_leakage+sensor_offset",
                                                 "spool_lag+internal_leakage",
                                                 "valve_overlap+sensor_offset",
                                                 "coulomb_friction+valve_bias"};
  const auto& names = effect_names();
  if (kind == "library") {
    return {n % (names.size() + 1) < names.size() ? names[n % (names.size() + 1)] : "none", base};
  }
  if (kind == "pair") return {pairs[n % pairs.size()], base};
  if (kind == "warmup_temp" || kind == "warmup_no_temp") {
    base.record_temperature = kind == "warmup_temp";
    return {"oil_temperature", base};
  }
  if (kind == "edge" || kind == "beyond") {
    base.edge = kind == "edge" ? 1.0 : 1.5;
    return {names[n % names.size()], base};
  }
  if (kind == "clean") return {"none", base};
  if (kind == "misstated") {
    base.misstate = misstatements()[n % misstatements().size()].key;
    return {"none", base};
  }
  if (kind == "onset") {
    base.onset = true;
    return {onset_effects()[n % onset_effects().size()], base};
  }
  throw std::invalid_argument(fmt::format("unknown case class '{}'", kind));
}

namespace {

bool has(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

std::string EvaluationSummary::kind_markdown() const {
  std::string out =
      "| class | cases | target | met | `internal_leakage` named wrongly | `none` | `unexplained` "
      "| "
      "median NRMSE before / after / true / floor | median share of achievable improvement |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& kind : case_kinds()) {
    int n = 0, met = 0, wrong_leak = 0, nones = 0, unexplained = 0;
    std::vector<double> before, after, truth, floor, achieved;
    std::string target;
    for (const auto& c : cases) {
      if (c.kind != kind) continue;
      ++n;
      const bool leak_true = std::any_of(c.truths.begin(), c.truths.end(), [](const auto& t) {
        return t.effect == "internal_leakage";
      });
      wrong_leak += !leak_true && has(c.named_causes, "internal_leakage");
      nones += c.named == "none";
      unexplained += c.named == "unexplained";
      before.push_back(c.nrmse_before);
      after.push_back(c.nrmse_after);
      truth.push_back(c.nrmse_true);
      floor.push_back(c.nrmse_floor);
      if (!c.truths.empty() && kind != "warmup_no_temp") achieved.push_back(c.achieved);
      if (kind == "library" || kind == "edge" || kind == "beyond") {
        target = "cause right and main parameter within 25 %";
        met += c.parameter_within(0.25);
      } else if (kind == "pair") {
        target = "both named, no third";
        bool both = true;
        for (const auto& t : c.truths) both = both && has(c.named_causes, t.effect);
        met += both && c.named_causes.size() == c.truths.size();
      } else if (kind == "warmup_temp") {
        target = "oil_temperature named, visc_slope within 25 %";
        met += has(c.named_causes, "oil_temperature") &&
               std::abs(c.visc_estimate - c.true_value) <= 0.25 * c.true_value;
      } else if (kind == "warmup_no_temp") {
        target = "reported as drift (unexplained, drifts)";
        met += c.named == "unexplained" && c.drifts;
      } else if (kind == "clean") {
        target = "none";
        met += c.named == "none";
      } else if (kind == "misstated") {
        target = "rig_parameter names it, fitted within 10 %, nothing else named";
        met += c.misstatement_found(0.10);
      } else if (kind == "onset") {
        target = "the effect named alone, onset within 2 s";
        met += c.only_truth_named() && std::abs(c.onset_estimate - c.onset_true) <= 2.0;
      }
    }
    if (n == 0) continue;
    out += fmt::format(
        "| {} | {} | {} | {:.1f} % ({}) | {} | {} | {} | {:.4f} / {:.4f} / {:.4f} / {:.4f} | {} "
        "|\n",
        kind, n, target, 100.0 * met / n, met, wrong_leak, nones, unexplained, median(before),
        median(after), median(truth), median(floor),
        achieved.empty() ? std::string("-") : fmt::format("{:.2f}", median(achieved)));
  }
  return out;
}

std::string EvaluationSummary::targets_markdown() const {
  struct Count {
    int met = 0, of = 0;
    void add(bool ok) {
      met += ok;
      ++of;
    }
  };
  std::map<std::string, Count> counts;
  std::vector<double> achieved;
  double slowest = 0.0;
  for (const auto& c : cases) {
    slowest = std::max(slowest, c.seconds);
    if (!c.truths.empty() && c.kind != "warmup_no_temp") achieved.push_back(c.achieved);
    const bool single = c.kind == "library" || c.kind == "edge" || c.kind == "beyond";
    if (single && !c.truths.empty()) {
      const std::string where = c.kind == "library" ? "" : " (" + c.kind + ")";
      counts["single effects: cause right" + where].add(c.named == c.truth);
      counts["single effects: main parameter within 25 %" + where].add(c.parameter_within(0.25));
      counts["single effects: that effect alone named" + where].add(c.only_truth_named());
    }
    if (c.misstated.empty()) {
      counts["told the true rig: no rig_parameter named"].add(c.rig_findings.empty());
    }
    if (c.kind == "misstated") {
      bool named = false;
      for (const auto& f : c.rig_findings) named = named || f.parameter == c.misstated;
      const bool library = std::any_of(c.named_causes.begin(), c.named_causes.end(),
                                       [](const std::string& n) { return n != "rig_parameter"; });
      counts["misstated: rig_parameter names the value stated wrong"].add(named);
      counts["misstated: " + c.misstated + " named"].add(named);
      const double fitted = c.fitted_misstated();
      counts["misstated: fitted within 10 % of the true value"].add(
          named && std::abs(fitted - c.misstated_true) <= 0.1 * std::abs(c.misstated_true));
      counts["misstated: no library effect named"].add(!library);
      counts["misstated: all three"].add(c.misstatement_found(0.10));
    }
    if (c.kind == "onset") {
      const bool named = std::any_of(c.named_causes.begin(), c.named_causes.end(),
                                     [&](const std::string& n) { return n == c.truth; });
      counts["onset: the effect named"].add(named);
      counts["onset: named with its onset within 2 s"].add(
          named && std::abs(c.onset_estimate - c.onset_true) <= 2.0);
      counts["onset: the effect alone, onset within 2 s"].add(
          c.only_truth_named() && std::abs(c.onset_estimate - c.onset_true) <= 2.0);
      // An effect that shows only in motion and starts in a hold is placed within the hold.
      counts["onset: named, the true onset within the stretch reported (+-2 s)"].add(
          named && c.onset_true >= c.onset_earliest - 2.0 && c.onset_true <= c.onset_latest + 2.0);
    }
    if (c.kind == "pair") {
      bool both = true;
      for (const auto& t : c.truths) both = both && has(c.named_causes, t.effect);
      bool third = false;
      for (const auto& n : c.named_causes) {
        third = third || std::none_of(c.truths.begin(), c.truths.end(),
                                      [&](const TrueEffect& t) { return t.effect == n; });
      }
      counts["pairs: both named"].add(both);
      counts["pairs: no third effect named"].add(!third);
    }
    if (c.kind == "warmup_temp") {
      counts["warm-ups with temp: oil_temperature named, visc_slope within 25 %"].add(
          has(c.named_causes, "oil_temperature") &&
          std::abs(c.visc_estimate - c.true_value) <= 0.25 * c.true_value);
    }
    if (c.kind == "warmup_no_temp") {
      counts["warm-ups without temp: reported as drift"].add(c.named == "unexplained" && c.drifts);
      counts["warm-ups without temp: internal_leakage not named"].add(
          !has(c.named_causes, "internal_leakage"));
    }
    if (c.kind == "clean" || (c.kind == "library" && c.truths.empty())) {
      counts["clean data: none"].add(c.named == "none");
    }
    // `none` claims the nominal model is right; where an effect is present and the nominal
    // model misses the floor (DiagnosisSettings::floor_factor) it must not be said.
    if (!c.truths.empty() && c.nrmse_before > DiagnosisSettings{}.floor_factor * c.nrmse_floor) {
      counts["misfit above the floor: never none"].add(c.named != "none");
    }
  }
  std::string out = "| target | met |\n|---|---|\n";
  for (const auto& [name, n] : counts) {
    out += fmt::format("| {} | {:.1f} % ({} of {}) |\n", name, 100.0 * n.met / n.of, n.met, n.of);
  }
  if (!achieved.empty()) {
    out += fmt::format(
        "| share of the achievable improvement, median (warm-ups with temp "
        "included, without temp not) | {:.2f} ({} cases) |\n",
        median(achieved), achieved.size());
  }
  out += fmt::format("| slowest diagnosis (wall) | {:.1f} s |\n", slowest);
  return out;
}

}  // namespace leakmon::model
