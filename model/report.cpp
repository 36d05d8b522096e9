#include "model/report.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "model/result_json.hpp"
#include "sim/rig_description.hpp"

namespace leakmon::model {
namespace {

void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw ModelCheckError(fmt::format("{}: cannot write", path.string()));
}

std::string residual_csv(const MeasuredRecord& r, const Diagnosis& d) {
  const SegmentPredictor predictor(r, d.rig_check.assumed);
  Prediction before, after;
  predictor.predict(d.nominal, d.held_out_used, before);
  predictor.predict(d.extended, d.held_out_used, after);
  std::string out = "t,u,x,p1,p2,x_before,p1_before,p2_before,x_after,p1_after,p2_after\n";
  for (const auto& seg : d.held_out_used) {
    for (std::size_t k = seg.begin + 1; k < seg.begin + seg.length; ++k) {
      out += fmt::format(
          "{:.4f},{:.5g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},{:.7g},"
          "{:.7g}\n",
          r.t[k], r.u[k], r.x[k], r.p1[k], r.p2[k], before.x[k], before.p1[k], before.p2[k],
          after.x[k], after.p1[k], after.p2[k]);
    }
  }
  return out;
}

std::string parameter_lines(const std::vector<NamedValue>& params) {
  std::string out;
  for (const auto& p : params) {
    if (p.is_text()) {
      out += fmt::format("| {} | {} | |\n", p.name, p.text);
    } else if (p.name == "chamber") {
      out += fmt::format("| {} | {} | |\n", p.name, static_cast<int>(p.value));
    } else {
      out += fmt::format("| {} | {:.4g} | {:.2g} |\n", p.name, p.value, p.error);
    }
  }
  return out;
}

// An onset the data place exactly, or only within a stretch (an effect that shows once the
// piston moves, starting during a hold).
std::string onset_phrase(const NamedCause& cause) {
  if (cause.onset_s <= 0.0) return {};
  if (cause.onset_latest_s - cause.onset_earliest_s > 1.0) {
    return fmt::format(
        ", starting between t = {:.2f} s and {:.2f} s (any onset in that stretch fits the data "
        "alike: the effect shows only once the piston moves; {:.2f} s is its middle, marked on "
        "the residual plot)",
        cause.onset_earliest_s, cause.onset_latest_s, cause.onset_s);
  }
  return fmt::format(
      ", starting at t = {:.2f} s (absent before: the residual plot marks the onset)",
      cause.onset_s);
}

// The rig the model check assumed (FORMATS.md: the report states it), what it checked and
// what it changed from the stated values.
std::string rig_section(const Diagnosis& d) {
  const auto& c = d.rig_check;
  std::string out = "## The rig\n\n";
  out += fmt::format("Described as: {}{}.\n\n", sim::describe(d.rig),
                     d.rig.source.empty() ? std::string() : " (" + d.rig.source + ")");
  out += fmt::format(
      "Checked against the data (MODEL.md \"Other rigs\"): the supply, from the chamber "
      "levels p1 + p2 = ps + pt ({}: {:.4g} MPa at rest, {:.4g} MPa with the valve wide open, "
      "for a stated {:.4g} MPa), and the load stiffness given the stated area, from the force "
      "balance ({:.4g} +- {:.2g} kN/m for a stated {:.4g} kN/m; constant force {:.3g} N). Not "
      "checkable from u, x, p1, p2: the bore alone, the stroke and volumes (they trade with "
      "beta), u_max (trades with Kv); a slower spool or a larger null leakage is named as "
      "spool_lag or internal_leakage.\n\n",
      c.supply_column ? "from the ps column" : "from p1 + p2", c.sum_rest * 1e-6, c.sum_open * 1e-6,
      (c.stated.ps + c.stated.pt) * 1e-6, c.balance.K_s * 1e-3, c.balance.K_s_error * 1e-3,
      c.stated.K_s * 1e-3, c.balance.constant);
  if (c.findings.empty()) {
    out += "No stated value is contradicted: the model runs on the rig as described";
    if (!d.rig_rejected.empty()) {
      out += fmt::format(
          " (a correction of {} was tried, and did not predict the held-out data better: "
          "score {:.3f}, t {:.2f})",
          d.rig_rejected.front().parameter, d.rig_score, d.rig_significance);
    }
    out += ".\n\n";
  } else {
    out +=
        "**Stated values the data contradict** (cause `rig_parameter`; the effects below are "
        "judged on the corrected rig):\n\n| parameter | stated | fitted | standard error "
        "|\n|---|---|---|---|\n";
    for (const auto& f : c.findings) {
      out += fmt::format("| {} | {:.5g} | {:.5g} | {:.2g} |\n", f.parameter, f.stated, f.fitted,
                         f.error);
    }
    out += fmt::format(
        "\nThe calibrated nominal model on the stated rig scores a held-out NRMSE of {:.4f}, "
        "on the corrected rig {:.4f} (score {:.3f}, t {:.2f}).\n\n",
        d.nrmse_stated, d.nrmse_corrected, d.rig_score, d.rig_significance);
  }
  const auto [lower, upper] = calibration_bounds(Calibration::of(c.assumed));
  out += fmt::format(
      "Calibrated around the stated values (MODEL.md's ranges; the fit's bounds are twice "
      "them): beta {:.4g} GPa ({:.3g}-{:.3g}), Kv {:.4g} ({:.3g}-{:.3g}), m {:.4g} kg "
      "({:.3g}-{:.3g}), b {:.4g} N s/m ({:.3g}-{:.3g}).\n\n",
      c.assumed.beta * 1e-9, lower.beta * 1e-9, upper.beta * 1e-9, c.assumed.Kv, lower.Kv, upper.Kv,
      c.assumed.m, lower.m, upper.m, c.assumed.b, lower.b, upper.b);
  return out;
}

std::string markdown(const MeasuredRecord& r, const Diagnosis& d, bool plots) {
  std::string out = fmt::format("# Model check of {}\n\n", r.source);
  out += fmt::format(
      "{:.1f} s at {:.0f} Hz; the model was fitted on {} segments of the fitting "
      "part and scored on {} held-out segments (open-loop simulation on the "
      "measured command from the measured state, see docs/model-check.md).\n\n",
      r.duration(), 1.0 / r.dt, d.fitting_used.size(), d.held_out_used.size());
  for (const auto& c : r.censored) {
    if (c.reason == MeasuredRecord::Censored::Reason::range_end) {
      out += fmt::format(
          "{} sits at its largest reading, {:.4g} MPa, on {} samples (the first at {}): a "
          "transducer's range end, which the pressure went past. Those samples say only \"at "
          "least this much\" and are left out like gaps; a transducer with more range would "
          "keep them.\n\n",
          c.channel, c.value * 1e-6, c.samples, c.first);
    } else if (c.reason == MeasuredRecord::Censored::Reason::spikes) {
      out += fmt::format(
          "{} spikes: {} isolated samples (the first at {}, the largest {:.4g} off) were replaced "
          "by the median of their neighbours.\n\n",
          c.channel, c.samples, c.first, c.value);
    } else {
      out += fmt::format(
          "{} holds one exact value for {} s or longer {} time(s), {} samples in all (the first "
          "at {}, reading {:.6g}): a frozen, dropped-out or saturated transducer, since a "
          "working one moves by about an LSB even at rest. Left out like gaps.\n\n",
          c.channel, c.held_min_s, c.runs, c.samples, c.first, c.value);
    }
  }
  out += rig_section(d);
  out += "## Verdict\n\n";
  out += fmt::format(
      "Noise floor: the held-out NRMSE that the noise alone leaves, from this capture's "
      "transducer noise (x {:.3g} m, p1 {:.3g} Pa, p2 {:.3g} Pa) and the spool flow noise: "
      "**{:.4f}**. The calibrated nominal model scores {:.4f}.\n\n",
      d.noise.x, d.noise.p1, d.noise.p2, d.nrmse_floor, d.nrmse_before);
  if (d.cause == "none") {
    out +=
        "The calibrated nominal model reaches the noise floor and no effect of the library "
        "predicts the held-out data significantly better: the simulation agrees with the "
        "measurement within the noise.\n\n";
  } else if (d.cause == "unexplained") {
    out += fmt::format(
        "**Unexplained misfit.** The calibrated nominal model misses the noise floor "
        "({:.4f} against {:.4f}) and {}.\n\n",
        d.nrmse_before, d.nrmse_floor,
        d.drifts ? "the effect that would fit it on average does not hold still over the "
                   "capture (see Drift): the rig's operating conditions change, which a "
                   "constant fault such as internal leakage does not explain"
                 : "no effect of the library, alone or combined, explains it");
  } else {
    out += fmt::format(
        "The nominal model misses **{}**. Extending the model with {} lowers the "
        "held-out NRMSE from {:.4f} to {:.4f}.\n\n",
        d.cause, d.causes.size() > 1 ? "them" : "it", d.nrmse_before, d.nrmse_after);
    for (const auto& cause : d.causes) {
      if (cause.effect == "rig_parameter") continue;  // in "The rig" below
      out +=
          fmt::format("**{}**{}\n\n| parameter | fitted value | standard error |\n|---|---|---|\n",
                      cause.effect, onset_phrase(cause));
      out += parameter_lines(cause.params) + "\n";
    }
  }
  if (!d.steps.empty()) {
    out +=
        "Forward selection (each step fitted jointly with the calibration and the effects "
        "before it; gain on held-out data over the previous step's model):\n\n"
        "| step | effect | held-out NRMSE | score | significance | named |\n"
        "|---|---|---|---|---|---|\n";
    for (std::size_t i = 0; i < d.steps.size(); ++i) {
      const auto& st = d.steps[i];
      const std::string effect = st.replaces.empty()
                                     ? st.effect
                                     : fmt::format("{} in place of {}", st.effect, st.replaces);
      out += fmt::format("| {} | {} | {:.4f} | {:.4f} | {:.2f} | {} |\n", i + 1, effect, st.nrmse,
                         st.score, st.significance, st.accepted ? "yes" : "no");
    }
    out += "\n";
  }
  if (d.unexplained) {
    out += "## Where the misfit lives\n\n" + describe(*d.unexplained) + "\n\n";
  }
  if (!d.at_bound.empty() || !d.nominal_at_bound.empty()) {
    out += "**Calibration on a bound**: ";
    for (const auto& name : d.at_bound) out += name + " ";
    if (!d.nominal_at_bound.empty()) {
      out += "(calibrated nominal model: ";
      for (const auto& name : d.nominal_at_bound) out += name + " ";
      out += ")";
    }
    out +=
        ". A calibrated value on its bound is not a calibration: the model compensates for "
        "something it lacks (the fit was retried from the starts the effect candidates "
        "suggested).\n\n";
  }
  if (!d.drift.empty()) {
    out +=
        "## Drift (first third against last third of the capture)\n\n"
        "| parameter | first third | last third | z | drifts |\n|---|---|---|---|---|\n";
    for (const auto& c : d.drift) {
      out +=
          fmt::format("| {} | {:.4g} +- {:.2g} | {:.4g} +- {:.2g} | {:.1f} | {} |\n", c.parameter,
                      c.early, c.early_error, c.late, c.late_error, c.z, c.drifts ? "yes" : "no");
    }
    out += "\n";
  }
  out +=
      "## Calibration (fitted, not a cause)\n\n| parameter | value | standard error |\n"
      "|---|---|---|\n";
  const auto& c = d.calibrated;
  const auto& e = d.calibrated_errors;
  out += fmt::format(
      "| beta | {:.4g} Pa | {:.2g} |\n| Kv | {:.4g} | {:.2g} |\n| m | {:.4g} kg | "
      "{:.2g} |\n| b | {:.4g} N s/m | {:.2g} |\n\n",
      c.beta, e.beta, c.Kv, e.Kv, c.m, e.m, c.b, e.b);
  out +=
      "Standard errors come from the Gauss-Newton covariance of the fit; residuals within a "
      "segment are correlated, so they are optimistic.\n\n";
  if (d.force_balance.windows > 0) {
    out += fmt::format(
        "The measured force balance (docs/model-check.md) gives m = {:.4g} +- {:.2g} kg and "
        "b = {:.4g} +- {:.2g} N s/m over {} windows{}.\n\n",
        d.force_balance.m, d.force_balance.m_error, d.force_balance.b, d.force_balance.b_error,
        d.force_balance.windows,
        usable(d.force_balance, d.rig_check.assumed.m) ? "; m is taken from it, b starts from it"
                                                       : "; not usable here, so m is fitted");
  }
  if (d.ripple_line) {
    out += fmt::format(
        "Supply-ripple line test on {}: most prominent line at {:.4f} Hz, coherent second-half "
        "statistic z = {:.2f} (N(0, 1) without a ripple; a ripple is a candidate from z >= "
        "{:.1f}).\n\n",
        d.ripple_line->from_supply_column ? "the supply pressure ps" : "p1 + p2",
        d.ripple_line->frequency_hz, d.ripple_line->held_out_z, d.min_line_z);
  }
  out +=
      "## Ranking of the effect library (held-out data)\n\n| effect | score | significance "
      "(t) | physical | parameters |\n|---|---|---|---|---|\n";
  for (const auto& rk : d.ranking) {
    std::string params;
    for (const auto& p : rk.params) {
      params += p.is_text() ? fmt::format("{}={} ", p.name, p.text)
                            : fmt::format("{}={:.3g} ", p.name, p.value);
    }
    out += fmt::format("| {} | {:.3f} | {:.1f} | {} | {} |\n", rk.effect, rk.score, rk.significance,
                       rk.plausible ? "yes" : "no", params);
  }
  out +=
      "\nscore: share of the calibrated nominal model's held-out squared error that the "
      "extension removes; significance: paired t statistic over held-out segments.\n\n";
  if (plots) {
    out +=
        "## Where it shows\n\n"
        "![residual time series](residuals_time.png)\n\n"
        "Residuals (simulation minus measurement) of the nominal and extended model; a "
        "vertical line marks where a named effect starts.\n\n"
        "![residuals against physical regressors](residuals_regressors.png)\n\n"
        "Nominal-model residuals against load pressure p1-p2, velocity, dp/dt, du/dt, "
        "command size and p1+p2: a leak follows load pressure, friction jumps with velocity "
        "sign, spool lag follows du/dt, overlap shows for small commands.\n\n"
        "![residual spectra](residuals_spectrum.png)\n\n"
        "Residual spectra: a supply ripple is a line.\n";
  } else {
    out += "(The plots could not be drawn: /usr/bin/python3 with matplotlib is needed.)\n";
  }
  return out;
}

}  // namespace

bool write_report(const std::string& dir, const MeasuredRecord& record, const Diagnosis& d) {
  std::filesystem::create_directories(dir);
  const std::filesystem::path base(dir);
  write_file(base / "residuals.csv", residual_csv(record, d));
  write_file(base / "result.json", diagnosis_json(d));
  const std::string command =
      fmt::format("/usr/bin/python3 '{}' '{}' > '{}' 2>&1", LEAKMON_MODEL_PLOT_SCRIPT, dir,
                  (base / "plots.log").string());
  const bool plots = std::system(command.c_str()) == 0;
  write_file(base / "report.md", markdown(record, d, plots));
  return plots;
}

}  // namespace leakmon::model
