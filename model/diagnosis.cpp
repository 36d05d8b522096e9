#include "model/diagnosis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

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

  if (auto line = find_spectral_line(record)) d.ripple_line_hz = line->frequency_hz;
  const auto library = effect_library(d.ripple_line_hz.value_or(0.0));

  // Screening: each candidate fitted together with the calibration on a few segments, from the
  // catalogue calibration (not from the nominal fit: a large effect distorts the nominal fit,
  // which then leads the solver into a compensating local minimum).
  const auto screening_segments = spread(d.fitting_used, settings.screening_segments);
  FitSettings screening = settings.fit;
  screening.max_iterations = settings.screening_iterations;
  std::vector<FitResult> screened;
  const FitResult* best_screened = nullptr;
  for (const auto& candidate : library) {
    screened.push_back(
        fit_model(predictor, screening_segments, &candidate, Calibration{}, screening));
  }
  for (const auto& fit : screened) {
    if (!best_screened || fit.cost < best_screened->cost) best_screened = &fit;
  }

  // The calibrated nominal model: the better of two local fits, from the catalogue and from the
  // best screened calibration (the nominal fit's cost surface has local minima of its own).
  FitResult nominal = fit_model(predictor, d.fitting_used, nullptr, Calibration{}, settings.fit);
  if (best_screened) {
    FitResult other = fit_model(predictor, d.fitting_used, nullptr,
                                best_screened->parameters.calibration, settings.fit);
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
    r.significance = paired_t(nominal_errors, errors);
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
  for (const auto& name : leaders) {
    if (best[name].score <= 0.0) continue;
    EffectCandidate& candidate = best_candidate[name];
    for (std::size_t i = 0; i < candidate.parameters.size(); ++i) {
      auto& fp = candidate.parameters[i];
      fp.initial = std::clamp(best[name].fit.values[i], fp.lower, fp.upper);
    }
    RankedEffect refined =
        score(candidate, fit_model(predictor, d.fitting_used, &candidate,
                                   best[name].fit.parameters.calibration, settings.fit));
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
  const RankedEffect* winner = nullptr;
  for (const auto& r : d.ranking) {
    if (r.plausible && r.refined) {
      winner = &r;
      break;
    }
  }
  FitSettings with_errors = settings.fit;
  with_errors.uncertainties = true;
  if (winner && winner->score >= settings.min_score &&
      winner->significance >= settings.min_significance) {
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
  d.nrmse_after = predictor.nrmse(d.extended, d.held_out_used);
  return d;
}

}  // namespace leakmon::model
