#include "model/diagnosis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "model/force_balance.hpp"
#include "model/spectral_line.hpp"

namespace leakmon::model {
namespace {

// Mean squared scaled residual of each segment.
std::vector<double> segment_errors(const SegmentPredictor& predictor,
                                   const ModelParameters& parameters,
                                   std::span<const Segment> segments) {
  std::vector<double> r(SegmentPredictor::residual_count(segments));
  predictor.residuals(parameters, segments, r);
  std::vector<double> out;
  std::size_t i = 0;
  for (const auto& seg : segments) {
    const std::size_t n = 3 * (seg.length - 1);
    double sum = 0.0;
    for (std::size_t j = 0; j < n; ++j, ++i) sum += r[i] * r[i];
    out.push_back(sum / static_cast<double>(n));
  }
  return out;
}

// Mean over held-out segments of log(error before / error after): a geometric mean, so one
// segment where an extension diverges cannot outweigh all the others (nor one lucky segment).
double mean_log_ratio(const std::vector<double>& before, const std::vector<double>& after) {
  double sum = 0.0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    sum += std::log(std::max(before[i], 1e-300) / std::max(after[i], 1e-300));
  }
  return sum / static_cast<double>(std::max<std::size_t>(before.size(), 1));
}

// Paired t statistic of the per-segment log error ratio: each held-out segment is one
// comparison of the two models on the same data. The log keeps a few segments with a huge
// improvement (say, the only large steps) from hiding whether the gain is consistent.
double paired_t(const std::vector<double>& before, const std::vector<double>& after) {
  const auto n = static_cast<double>(before.size());
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    const double d = std::log(std::max(before[i], 1e-300) / std::max(after[i], 1e-300));
    sum += d;
    sum2 += d * d;
  }
  const double mean = sum / n;
  const double var = std::max(sum2 / n - mean * mean, 1e-300) * n / std::max(n - 1.0, 1.0);
  return mean / std::sqrt(var / n);
}

// Yuen's trimmed paired t statistic of the same log ratios (20 % trimmed from each end,
// winsorised variance): a real effect often shows in a few segments only (entrained air where a
// chamber pressure is low, a transducer lag at fast pressure changes), and those few large
// gains inflate the plain t statistic's variance until it hides the consistent small gain of
// the bulk. Trimming both ends keeps the statistic symmetric under "no gain".
double trimmed_t(const std::vector<double>& before, const std::vector<double>& after) {
  std::vector<double> d;
  for (std::size_t i = 0; i < before.size(); ++i) {
    d.push_back(std::log(std::max(before[i], 1e-300) / std::max(after[i], 1e-300)));
  }
  const std::size_t n = d.size();
  const std::size_t g = n / 5;
  if (n < 5 || n - 2 * g < 2) return 0.0;
  std::sort(d.begin(), d.end());
  double trimmed_mean = 0.0;
  for (std::size_t i = g; i < n - g; ++i) trimmed_mean += d[i];
  trimmed_mean /= static_cast<double>(n - 2 * g);
  double winsor_mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) winsor_mean += d[std::clamp(i, g, n - g - 1)];
  winsor_mean /= static_cast<double>(n);
  double winsor_ss = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = d[std::clamp(i, g, n - g - 1)] - winsor_mean;
    winsor_ss += w * w;
  }
  const auto h = static_cast<double>(n - 2 * g);
  const double standard_error = std::sqrt(std::max(winsor_ss, 1e-300) / (h * (h - 1.0)));
  return trimmed_mean / standard_error;
}

std::vector<NamedValue> named_values(const EffectCandidate& c, const FitResult& fit) {
  std::vector<NamedValue> out;
  if (c.effect == "supply_ripple") {
    // Solver-side the ripple has sin and cos amplitudes; MODEL.md's dP is its amplitude.
    const double amplitude = std::hypot(fit.values[0], fit.values[2]);
    const double err = fit.value_errors.empty() ? 0.0 : fit.value_errors[0];
    out.push_back({"dP", amplitude, err, ""});
    out.push_back({"f", fit.values[1], fit.value_errors.empty() ? 0.0 : fit.value_errors[1], ""});
    return out;
  }
  for (std::size_t i = 0; i < c.parameters.size(); ++i) {
    if (c.parameters[i].name.empty()) continue;
    out.push_back({c.parameters[i].name, fit.values[i],
                   fit.value_errors.empty() ? 0.0 : fit.value_errors[i], ""});
  }
  if (c.effect == "external_leakage")
    out.push_back({"chamber", c.variant == "chamber 2" ? 2.0 : 1.0, 0.0, ""});
  if (c.effect == "sensor_offset" || c.effect == "sensor_lag") {
    out.push_back({"channel", 0.0, 0.0, c.variant});
  }
  return out;
}

}  // namespace

Diagnosis diagnose(const MeasuredRecord& record, const DiagnosisSettings& settings) {
  Diagnosis d;
  d.plan = split_record(record, settings.split);
  if (d.plan.fitting.size() < 4 || d.plan.held_out.size() < 4) {
    throw ModelCheckError(fmt::format(
        "{}: only {} fitting and {} held-out segments without gaps; the model check needs at "
        "least 4 of each",
        record.source, d.plan.fitting.size(), d.plan.held_out.size()));
  }
  d.fitting_used = spread(d.plan.fitting, settings.max_fitting_segments);
  d.held_out_used = spread(d.plan.held_out, settings.max_held_out_segments);
  const SegmentPredictor predictor(record);

  // Only a line that passes its second-half test is worth a ripple candidate: without one the
  // ripple fit would merely chase the tallest noise peak.
  d.ripple_line = find_spectral_line(record);
  d.min_line_z = settings.min_line_z;
  d.ripple_line_significant = d.ripple_line && d.ripple_line->held_out_z >= settings.min_line_z;
  const auto library =
      effect_library(d.ripple_line_significant ? d.ripple_line->frequency_hz : 0.0);

  // m from the measured force balance, where it is usable: the simulation fit then calibrates
  // beta, Kv and b (from the force balance's b), and cannot slide along the beta/m/b valley.
  // b stays free: in the force balance it shares the moving windows with the friction term.
  d.force_balance = estimate_force_balance(record, d.plan.fitting);
  Calibration catalogue;  // MODEL.md's values, m and b measured when possible
  FitSettings fit_settings = settings.fit;
  if (settings.use_force_balance && usable(d.force_balance)) {
    catalogue.m = d.force_balance.m;
    catalogue.b = d.force_balance.b;
    fit_settings.free_calibration = {true, true, false, true};
  }

  // Screening: each candidate fitted together with the calibration on a few segments, from the
  // catalogue calibration (not from the nominal fit: a large effect distorts the nominal fit,
  // which then leads the solver into a compensating local minimum).
  const auto screening_segments = spread(d.fitting_used, settings.screening_segments);
  FitSettings screening = fit_settings;
  screening.max_iterations = settings.screening_iterations;
  std::vector<FitResult> screened;
  const FitResult* best_screened = nullptr;
  for (const auto& candidate : library) {
    screened.push_back(fit_model(predictor, screening_segments, &candidate, catalogue, screening));
  }
  for (const auto& fit : screened) {
    if (!best_screened || fit.cost < best_screened->cost) best_screened = &fit;
  }

  // The calibrated nominal model: the better of two local fits, from the catalogue and from the
  // best screened calibration (the nominal fit's cost surface has local minima of its own).
  FitResult nominal = fit_model(predictor, d.fitting_used, nullptr, catalogue, fit_settings);
  if (best_screened) {
    FitResult other = fit_model(predictor, d.fitting_used, nullptr,
                                best_screened->parameters.calibration, fit_settings);
    if (other.cost < nominal.cost) nominal = std::move(other);
  }
  d.nominal = nominal.parameters;
  const std::vector<double> nominal_errors =
      segment_errors(predictor, nominal.parameters, d.held_out_used);

  const auto score = [&](const EffectCandidate& candidate, FitResult fit) {
    RankedEffect r;
    r.effect = candidate.effect;
    const auto errors = segment_errors(predictor, fit.parameters, d.held_out_used);
    r.score = 1.0 - std::exp(-mean_log_ratio(nominal_errors, errors));
    r.significance = std::max(paired_t(nominal_errors, errors), trimmed_t(nominal_errors, errors));
    r.plausible = candidate.plausible(fit.values);
    r.params = named_values(candidate, fit);
    r.fit = std::move(fit);
    return r;
  };
  // Best variant of each effect (e.g. the chamber that leaks), by held-out error.
  std::map<std::string, RankedEffect> best;
  std::map<std::string, EffectCandidate> best_candidate;
  for (std::size_t i = 0; i < library.size(); ++i) {
    const auto& candidate = library[i];
    RankedEffect r = score(candidate, std::move(screened[i]));
    auto it = best.find(candidate.effect);
    if (it == best.end() || r.score > it->second.score) {
      best[candidate.effect] = std::move(r);
      best_candidate[candidate.effect] = candidate;
    }
  }
  // Refinement: the leading effects fitted together with the calibration on every fitting
  // segment, from their screening values.
  std::vector<std::string> leaders;
  for (const auto& [name, r] : best) leaders.push_back(name);
  std::stable_sort(leaders.begin(), leaders.end(),
                   [&](const auto& a, const auto& b) { return best[a].score > best[b].score; });
  leaders.resize(std::min(leaders.size(), settings.refined_effects));
  // A significant line is evidence of its own (its held-out gain in x, p1, p2 is small next
  // to the spool flow noise, so the screening score alone may leave it out).
  if (best.contains("supply_ripple") &&
      std::find(leaders.begin(), leaders.end(), "supply_ripple") == leaders.end()) {
    leaders.push_back("supply_ripple");
  }
  // Screening's few solver steps may leave the calibration worse than the nominal fit's (all
  // screened scores negative, even for the true effect): each refinement starts from whichever
  // calibration, with the screened effect, fits the fitting segments better.
  const auto fitting_cost = [&](const EffectCandidate& candidate, const Calibration& calibration) {
    ModelParameters p;
    p.calibration = calibration;
    std::vector<double> values;
    for (const auto& fp : candidate.parameters) values.push_back(fp.initial);
    candidate.apply(p.effects, values);
    double sum = 0.0;
    for (double e : segment_errors(predictor, p, d.fitting_used)) sum += e;
    return sum;
  };
  for (const auto& name : leaders) {
    EffectCandidate& candidate = best_candidate[name];
    for (std::size_t i = 0; i < candidate.parameters.size(); ++i) {
      auto& fp = candidate.parameters[i];
      fp.initial = std::clamp(best[name].fit.values[i], fp.lower, fp.upper);
    }
    const Calibration& screened_calibration = best[name].fit.parameters.calibration;
    const Calibration& start = fitting_cost(candidate, nominal.parameters.calibration) <
                                       fitting_cost(candidate, screened_calibration)
                                   ? nominal.parameters.calibration
                                   : screened_calibration;
    RankedEffect refined =
        score(candidate, fit_model(predictor, d.fitting_used, &candidate, start, fit_settings));
    refined.refined = true;
    best[name] = std::move(refined);
  }
  for (const auto& name : effect_names()) {
    auto it = best.find(name);
    if (it != best.end()) {
      d.ranking.push_back(std::move(it->second));
    } else {
      RankedEffect absent;  // supply_ripple without a spectral line: nothing to fit
      absent.effect = name;
      d.ranking.push_back(absent);
    }
  }
  std::stable_sort(d.ranking.begin(), d.ranking.end(),
                   [](const RankedEffect& a, const RankedEffect& b) { return a.score > b.score; });

  d.nrmse_before = predictor.nrmse(nominal.parameters, d.held_out_used);
  d.calibrated = nominal.parameters.calibration;
  d.extended = nominal.parameters;
  // The ripple is named on its line test (only then is it a candidate at all), as long as its
  // fit is physical and predicts the held-out data better (per segment and in NRMSE); any
  // other effect on the held-out gain of the best plausible extension.
  const RankedEffect* winner = nullptr;
  bool named = false;
  for (const auto& r : d.ranking) {
    if (r.effect == "supply_ripple" && r.plausible && r.refined && r.score > 0.0 &&
        predictor.nrmse(r.fit.parameters, d.held_out_used) < d.nrmse_before) {
      winner = &r;
      named = true;
    }
  }
  if (!winner) {
    for (const auto& r : d.ranking) {
      if (!r.plausible || !r.refined) continue;
      winner = &r;
      named = r.score >= settings.min_score && r.significance >= settings.min_significance;
      break;
    }
  }
  FitSettings with_errors = fit_settings;
  with_errors.uncertainties = true;
  if (named) {
    const EffectCandidate* candidate = &best_candidate.at(winner->effect);
    for (std::size_t i = 0; i < winner->fit.values.size(); ++i) {
      best_candidate.at(winner->effect).parameters[i].initial = winner->fit.values[i];
    }
    const FitResult fit = fit_model(predictor, d.fitting_used, candidate,
                                    winner->fit.parameters.calibration, with_errors);
    d.cause = winner->effect;
    d.params = named_values(*candidate, fit);
    d.extended = fit.parameters;
    d.calibrated = fit.parameters.calibration;
    d.calibrated_errors = fit.calibration_errors;
  } else {
    const FitResult fit =
        fit_model(predictor, d.fitting_used, nullptr, nominal.parameters.calibration, with_errors);
    d.calibrated_errors = fit.calibration_errors;
  }
  if (!fit_settings.free_calibration[2]) d.calibrated_errors.m = d.force_balance.m_error;
  d.nrmse_after = predictor.nrmse(d.extended, d.held_out_used);
  return d;
}

}  // namespace leakmon::model
