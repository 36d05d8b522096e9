#include "model/diagnosis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "model/change_point.hpp"
#include "model/force_balance.hpp"
#include "model/spectral_line.hpp"

namespace leakmon::model {
namespace {

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

// The share of `before`'s held-out error that `after` removes (the geometric mean above), and
// the evidence for it: the larger of the plain and the trimmed paired t. Every comparison of two
// models on held-out data (an effect, a further step, a swap, the stated rig) uses both.
double held_out_gain(const std::vector<double>& before, const std::vector<double>& after) {
  return 1.0 - std::exp(-mean_log_ratio(before, after));
}
double held_out_evidence(const std::vector<double>& before, const std::vector<double>& after) {
  return std::max(paired_t(before, after), trimmed_t(before, after));
}

// The parts of `joint` with the values fitted for them as their starting values: the causes
// named after a joint fit, each next fit starting where it left them.
std::vector<EffectCandidate> parts_from_fit(const EffectCandidate& joint,
                                            const std::vector<double>& values) {
  const auto shares = joint.split(values);
  std::vector<EffectCandidate> parts = joint.parts;
  for (std::size_t p = 0; p < parts.size(); ++p) {
    for (std::size_t k = 0; k < shares[p].size(); ++k)
      parts[p].parameters[k].initial = shares[p][k];
  }
  return parts;
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

// The bulk modulus at which the floor's draws ring as fast as the capture's pressures do
// (FloorRinging), or nothing where they already ring within `tolerance` (mean-square ratio) of
// the capture or where its fast pressure content is mostly transducer noise. The deterministic
// fit does not see beta on a rig whose hydraulic mode lies far above what the steps excite
// (seed 783005: beta fitted 43 % low, held-out error equal to the true model's), yet the
// spool flow noise that rings that mode makes most of the pressures' floor, in proportion to
// beta / V: the floor of the fitted model came out at 0.62 of what the true model scores. The
// ringing is read off the data, so a model that damps or softens it wrongly is not trusted
// for the floor. Bisection in log beta within the calibration's bounds (the ringing grows with
// beta), on a subset of the segments with one draw each.
std::optional<double> ringing_beta(const SegmentPredictor& predictor, ModelParameters model,
                                   std::span<const Segment> segments, const NoiseLevels& noise,
                                   const FloorRinging& ringing, const Calibration& stated,
                                   const DiagnosisSettings& settings) {
  const double transducers = 20.0 * (noise.p1 * noise.p1 + noise.p2 * noise.p2);
  if (!(ringing.measured > settings.ringing_transducer_ratio * transducers) ||
      !(ringing.drawn > 0.0))
    return std::nullopt;
  const double ratio = ringing.drawn / ringing.measured;
  if (ratio < settings.ringing_tolerance && ratio > 1.0 / settings.ringing_tolerance)
    return std::nullopt;
  const auto subset = spread(segments, settings.ringing_segments);
  const auto [lower, upper] = calibration_bounds(stated);
  const auto excess = [&](double beta) {  // log(drawn / measured) at this beta
    model.calibration.beta = beta;
    FloorRinging r;
    predictor.noise_floor(model, subset, noise, settings.floor_seed, 1, settings.floor_noise_pieces,
                          &r);
    return std::log(std::max(r.drawn, 1e-300) / std::max(r.measured, 1e-300));
  };
  double lo = std::log(lower.beta), hi = std::log(upper.beta);
  if (excess(std::exp(lo)) >= 0.0) return std::exp(lo);
  if (excess(std::exp(hi)) <= 0.0) return std::exp(hi);
  for (int i = 0; i < settings.ringing_bisections; ++i) {
    const double mid = 0.5 * (lo + hi);
    (excess(std::exp(mid)) < 0.0 ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi));
}

// Neither a ripple (found by its line) nor the oil (by its temperature) starts at a time.
bool starts_at_a_time(const EffectCandidate& c) {
  return c.effect != "supply_ripple" && c.effect != "oil_temperature";
}

}  // namespace

NamedCause rig_cause(const RigFinding& finding) {
  return {"rig_parameter",
          {{"parameter", 0.0, 0.0, finding.parameter},
           {"stated", finding.stated, 0.0, ""},
           {"fitted", finding.fitted, finding.error, ""}},
          0.0};
}

Diagnosis diagnose(const MeasuredRecord& record, const DiagnosisSettings& settings) {
  return diagnose(record, sim::RigDescription::paper(), settings);
}

Diagnosis diagnose(const MeasuredRecord& record, const sim::RigDescription& rig,
                   const DiagnosisSettings& settings) {
  Diagnosis d;
  d.rig = rig;
  d.plan = split_record(record, settings.split);
  if (d.plan.fitting.size() < 4 || d.plan.held_out.size() < 4) {
    // Samples left out as clipping or a frozen transducer break segments as gaps do; a rig
    // whose pressures ring past the transducers' range end every few tens of milliseconds
    // leaves no whole segment, and the user must learn that it is the range, not the capture.
    std::string left_out;
    for (const auto& c : record.censored) {
      if (c.reason == MeasuredRecord::Censored::Reason::spikes) continue;
      left_out += fmt::format("{}{} {} on {} samples from {}",
                              left_out.empty() ? "; left out as such: " : ", ", c.channel,
                              c.reason == MeasuredRecord::Censored::Reason::range_end
                                  ? fmt::format("at its range end ({:.4g} MPa)", c.value * 1e-6)
                                  : std::string("holding one value"),
                              c.samples, c.first);
    }
    throw ModelCheckError(fmt::format(
        "{}: only {} fitting and {} held-out {} s segments without gaps or left-out samples{}; "
        "the model check needs at least 4 of each",
        record.source, d.plan.fitting.size(), d.plan.held_out.size(), settings.split.segment_s,
        left_out));
  }
  d.fitting_used = spread(d.plan.fitting, settings.max_fitting_segments);
  d.held_out_used = spread(d.plan.held_out, settings.max_held_out_segments);

  // The stated values first: a contradicted one is corrected before any effect is judged, and
  // named when the corrected rig's calibrated nominal model predicts the held-out data better.
  d.rig_check = check_rig(record, d.plan.fitting, rig.params, settings.rig);
  if (!d.rig_check.findings.empty()) {
    // The calibrated nominal model on a rig: m from the force balance where usable.
    const auto calibrated_nominal = [&](const sim::Parameters& on) {
      const SegmentPredictor p(record, on);
      FitSettings fs = settings.fit;
      fs.stated = Calibration::of(on);
      Calibration start = Calibration::of(on);
      const ForceBalance fb = estimate_force_balance(record, d.plan.fitting, on);
      if (settings.use_force_balance && usable(fb, on.m)) {
        start.m = fb.m;
        start.b = fb.b;
        fs.free_calibration = {true, true, false, true};
      }
      const FitResult fit = fit_model(p, d.fitting_used, nullptr, start, fs);
      return std::pair{segment_errors(p, fit.parameters, d.held_out_used),
                       p.nrmse(fit.parameters, d.held_out_used)};
    };
    const auto [stated_errors, stated_nrmse] = calibrated_nominal(d.rig_check.stated);
    const auto [corrected_errors, corrected_nrmse] = calibrated_nominal(d.rig_check.assumed);
    d.nrmse_stated = stated_nrmse;
    d.nrmse_corrected = corrected_nrmse;
    d.rig_score = held_out_gain(stated_errors, corrected_errors);
    d.rig_significance = held_out_evidence(stated_errors, corrected_errors);
    if (d.rig_score < settings.min_score || d.rig_significance < settings.min_significance ||
        corrected_nrmse >= stated_nrmse) {
      d.rig_rejected = std::move(d.rig_check.findings);
      d.rig_check.findings.clear();
      d.rig_check.assumed = d.rig_check.stated;
    }
  }
  const sim::Parameters& assumed = d.rig_check.assumed;
  const Calibration stated_calibration = Calibration::of(assumed);
  const SegmentPredictor predictor(record, assumed);

  // Only a line that passes its second-half test is worth a ripple candidate: without one the
  // ripple fit would merely chase the tallest noise peak.
  d.ripple_line = find_spectral_line(record);
  d.min_line_z = settings.min_line_z;
  d.ripple_line_significant = d.ripple_line && d.ripple_line->held_out_z >= settings.min_line_z;
  const auto library = effect_library(d.ripple_line_significant ? d.ripple_line->frequency_hz : 0.0,
                                      !record.temp.empty(), record.dt, assumed);

  // m from the measured force balance, where it is usable: the simulation fit then calibrates
  // beta, Kv and b (from the force balance's b), and cannot slide along the beta/m/b valley.
  // b stays free: in the force balance it shares the moving windows with the friction term.
  d.force_balance = estimate_force_balance(record, d.plan.fitting, assumed);
  Calibration catalogue = stated_calibration;  // the rig's values, m and b measured if possible
  FitSettings fit_settings = settings.fit;
  fit_settings.stated = stated_calibration;
  if (settings.use_force_balance && usable(d.force_balance, assumed.m)) {
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
  // A calibration on its bounds is the model compensating for something it lacks (a strong
  // droop drove beta, Kv and b to their limits): retry from the calibrations that the best
  // screened effect candidates reached, moved inside the bounds.
  d.nominal_at_bound = calibration_at_bound(nominal.parameters.calibration, stated_calibration);
  if (!d.nominal_at_bound.empty()) {
    std::vector<const FitResult*> starts;
    for (const auto& fit : screened) starts.push_back(&fit);
    std::stable_sort(starts.begin(), starts.end(),
                     [](const FitResult* a, const FitResult* b) { return a->cost < b->cost; });
    starts.resize(std::min<std::size_t>(starts.size(), 3));
    for (const FitResult* start : starts) {
      FitResult retry =
          fit_model(predictor, d.fitting_used, nullptr,
                    within_bounds(start->parameters.calibration, stated_calibration), fit_settings);
      if (retry.cost < nominal.cost) nominal = std::move(retry);
    }
    // Or the rig's own lightly damped mode, rung in the pressures, is matched only by a beta
    // within a few per cent of the true one, and from further away the fit damps it out (b on
    // its upper bound) and stops: beta scanned on a grid first (seed 770009: a slow 18.8 ms
    // spool, the stated beta 15 % low; every start ended there, 1.2 x the true model's error).
    FitResult scanned = fit_model(
        predictor, d.fitting_used, nullptr,
        best_beta_on_grid(predictor, d.fitting_used, catalogue, stated_calibration), fit_settings);
    if (scanned.cost < nominal.cost) nominal = std::move(scanned);
    d.nominal_at_bound = calibration_at_bound(nominal.parameters.calibration, stated_calibration);
  }
  d.nominal = nominal.parameters;
  // What a correct model would score on these held-out segments, from the capture's own
  // transducer noise and the spool flow noise.
  d.noise = predictor.noise_levels();
  FloorRinging ringing;
  d.channel_floor =
      predictor.noise_floor(nominal.parameters, d.held_out_used, d.noise, settings.floor_seed,
                            settings.floor_repeats, settings.floor_noise_pieces, &ringing);
  d.floor_ringing = ringing;
  if (const auto beta = ringing_beta(predictor, nominal.parameters, d.held_out_used, d.noise,
                                     ringing, stated_calibration, settings)) {
    ModelParameters ringing_model = nominal.parameters;
    ringing_model.calibration.beta = *beta;
    d.floor_beta = *beta;
    d.channel_floor =
        predictor.noise_floor(ringing_model, d.held_out_used, d.noise, settings.floor_seed,
                              settings.floor_repeats, settings.floor_noise_pieces);
  }
  d.nrmse_floor = (d.channel_floor[0] + d.channel_floor[1] + d.channel_floor[2]) / 3.0;
  const std::vector<double> nominal_errors =
      segment_errors(predictor, nominal.parameters, d.held_out_used);

  // Effects that start inside the capture: where the calibrated nominal model's error steps up
  // at some time and stays up, the leading screened effects are also fitted from that time on
  // (onset variants, judged on held-out data against the constant ones like any variant). A
  // segment's error follows its operating point (a large step against a rest) far more than a
  // fault's onset, so the split is also sought in what a leading (constant) candidate gains
  // per segment over the nominal model: about nothing before the onset, and its gain after it.
  std::vector<EffectCandidate> candidates = library;
  const std::vector<Segment> in_time = segments_in_time_order(d.plan);
  std::vector<std::size_t> order(library.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return screened[a].cost < screened[b].cost;
  });
  // The leading screened effects that can start at a time, one variant each.
  std::vector<std::size_t> leading;
  for (const std::size_t i : order) {
    const auto& base = library[i];
    if (!starts_at_a_time(base)) continue;
    const bool seen = std::any_of(leading.begin(), leading.end(),
                                  [&](std::size_t j) { return library[j].effect == base.effect; });
    if (!seen) leading.push_back(i);
    if (leading.size() >= settings.onset_candidates) break;
  }
  // Every series' best split; the strongest is reported as the change point.
  std::vector<ChangePoint> splits;
  {
    // Each series is split over all segments and over the moving ones alone: an effect that
    // shows only while the piston moves (a supply droop, a slower spool) leaves the holds'
    // errors as they were, and among all segments the holds hid its onset (seed 796018: a droop
    // from 85.1 s, no onset variant tried, `unexplained`).
    const auto moving = moving_segments(record, in_time, settings.moving_share);
    std::vector<Segment> moving_in_time;
    for (const std::size_t i : moving) moving_in_time.push_back(in_time[i]);
    const auto split_both = [&](const std::vector<double>& values) {
      std::vector<double> of_moving;
      for (const std::size_t i : moving) of_moving.push_back(values[i]);
      for (auto split : {find_change_point(record, in_time, values),
                         find_change_point(record, moving_in_time, of_moving)}) {
        if (!split) continue;
        splits.push_back(*split);
        if (!d.change_point || split->statistic > d.change_point->statistic) {
          d.change_point = split;
        }
      }
    };
    const auto errors = segment_errors(predictor, nominal.parameters, in_time);
    std::vector<double> logs;
    for (double e : errors) logs.push_back(std::log(std::max(e, 1e-300)));
    split_both(logs);
    // ... and with the segments' excitation regressed out, against a test program's phases.
    if (auto split = find_change_point_beyond_excitation(record, in_time, logs,
                                                         segment_excitation(record, in_time))) {
      splits.push_back(*split);
    }
    for (std::size_t k = 0; k < std::min(leading.size(), settings.change_candidates); ++k) {
      const auto gained = segment_errors(predictor, screened[leading[k]].parameters, in_time);
      std::vector<double> gains;
      for (std::size_t i = 0; i < gained.size(); ++i) {
        gains.push_back(logs[i] - std::log(std::max(gained[i], 1e-300)));
      }
      split_both(gains);
    }
  }
  // Every candidate that can start at a time is tried from the change point, not only the
  // leading screened ones: fitted as constant effects, an effect that starts late in the
  // capture ranks below others that absorb part of its misfit everywhere (seed 796018's droop).
  const auto suggests_onset = [&](const ChangePoint& split) {
    return split.statistic >= settings.min_change_statistic ||
           (split.statistic >= settings.min_large_change_statistic &&
            split.step >= settings.large_change_step);
  };
  // Under a test program the nominal model's error follows the program (a hold's against a
  // sweep's), and its strongest split can be a phase change, not the effect: the splits of the
  // other series, far enough from the ones taken, are tried as well (818214: a hold ending at
  // 55 s split the errors at t 22; the candidates' gains split at the spool lag's 72.5 s, t 18,
  // never tried). The held-out data judge between the onsets as between any variants.
  std::stable_sort(splits.begin(), splits.end(), [](const ChangePoint& a, const ChangePoint& b) {
    return a.statistic > b.statistic;
  });
  for (const ChangePoint& split : splits) {
    if (d.onsets_tried.size() >= settings.onset_splits) break;
    if (!suggests_onset(split)) continue;
    const bool near_one_taken =
        std::any_of(d.onsets_tried.begin(), d.onsets_tried.end(), [&](const ChangePoint& taken) {
          return std::abs(taken.t_s - split.t_s) < settings.onset_split_separation_s;
        });
    if (near_one_taken) continue;
    d.onsets_tried.push_back(split);
    for (const auto& base : library) {
      if (!starts_at_a_time(base)) continue;
      EffectCandidate variant = base;
      variant.onset_s = split.t_s;
      screened.push_back(fit_model(predictor, screening_segments, &variant, catalogue, screening));
      candidates.push_back(std::move(variant));
    }
  }

  // The held-out segments that reach an onset and the nominal model's errors on them, kept
  // per onset (every onset variant of the screening shares the change point's).
  struct LaterHeldOut {
    std::vector<Segment> segments;
    std::vector<double> nominal_errors;
  };
  std::map<double, LaterHeldOut> later_by_onset;
  const auto later_held_out = [&](double onset_s) -> const LaterHeldOut& {
    auto [it, inserted] = later_by_onset.try_emplace(onset_s);
    if (inserted) {
      for (const Segment& seg : d.plan.held_out) {
        if (predictor.reaches(seg, onset_s)) it->second.segments.push_back(seg);
      }
      it->second.nominal_errors =
          segment_errors(predictor, nominal.parameters, it->second.segments);
    }
    return it->second;
  };
  const auto score = [&](const EffectCandidate& candidate, FitResult fit) {
    RankedEffect r;
    r.effect = candidate.effect;
    const auto errors = segment_errors(predictor, fit.parameters, d.held_out_used);
    r.score = held_out_gain(nominal_errors, errors);
    r.significance = held_out_evidence(nominal_errors, errors);
    // An effect that starts inside the capture can gain only on the segments that reach its
    // onset: over all of them, the earlier ones' zero gains dilute the paired t and the
    // trimmed t cuts the later ones' gains away as outliers (811067: a droop from 139.6 s of
    // 180 scored 0.19 at t 1.95, `unexplained`). Its evidence is also taken over every
    // held-out segment that reaches the onset (not only the spread `held_out_used` keeps: a
    // late onset leaves few of those); the score, a mean over every segment used, still
    // counts any loss before the onset.
    if (candidate.onset_s > 0.0) {
      const auto& later = later_held_out(candidate.onset_s);
      if (later.segments.size() >= settings.min_onset_segments) {
        const auto later_errors = segment_errors(predictor, fit.parameters, later.segments);
        r.significance = std::max({r.significance, paired_t(later.nominal_errors, later_errors),
                                   trimmed_t(later.nominal_errors, later_errors)});
      }
    }
    r.plausible = candidate.plausible(fit.values);
    r.params = named_values(candidate, fit);
    r.fit = std::move(fit);
    return r;
  };
  // Best variant of each effect (e.g. the chamber that leaks), by held-out error.
  std::map<std::string, RankedEffect> best;
  std::map<std::string, EffectCandidate> best_candidate;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const auto& candidate = candidates[i];
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
    candidate.apply(p, values);
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
  std::vector<std::string> names = effect_names();
  if (!record.temp.empty()) names.push_back("oil_temperature");
  for (const auto& name : names) {
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
  // The ripple is a candidate only on its line test, and named first when its fit is physical
  // and predicts the held-out data better with the same evidence as any effect (score and t):
  // a rig's own lightly damped hydraulic mode, rung by the spool flow noise, passes the line
  // test on other rigs, and a ripple fitted to it gained 0.0004 at t 0.4 and was named on a
  // healthy rig (issue 24's evaluation, seed 732007). Any other effect on the held-out gain of
  // the best plausible extension. An effect that gains more and is evidenced on its own comes
  // first, though: the ripple then earns its place as a forward step like any other effect. A line
  // that passed its test by chance, or a rig's own lightly damped hydraulic mode, gained nothing
  // (score 0.001) and was named ahead of a leak scoring 0.99 (issue 24's evaluation, seed 732024;
  // the paper's rig, seed 514079867).
  const auto evidenced = [&](const RankedEffect& r) {
    return r.plausible && r.refined && r.score >= settings.min_score &&
           r.significance >= settings.min_significance;
  };
  const RankedEffect* winner = nullptr;
  bool named = false;
  for (const auto& r : d.ranking) {
    const bool outranked = std::any_of(d.ranking.begin(), d.ranking.end(), [&](const auto& o) {
      return o.effect != "supply_ripple" && o.score > r.score && evidenced(o);
    });
    if (r.effect == "supply_ripple" && evidenced(r) && !outranked &&
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
  // A capture the calibrated nominal model already predicts about as well as a correct model
  // can has nothing left for an effect to explain: an extension that still gains there has
  // fitted the way the noise propagates, not a fault (seed 783005: entrained air named at 1.01
  // x the true model's held-out error). A ripple stands on its own line test.
  // Unless the extension predicts the held-out data better than the floor says any correct
  // model can: then the floor, not the effect, is wrong (a dead band's hunting is fast
  // pressure content the ringing match takes for noise: seed 782004, floor 0.29 against the
  // true model's 0.18).
  const auto at_floor = [&](double model_nrmse, double extended_nrmse) {
    return model_nrmse <= settings.name_floor_factor * d.nrmse_floor &&
           extended_nrmse * settings.name_floor_factor >= d.nrmse_floor;
  };
  if (named && winner->effect != "supply_ripple" &&
      at_floor(d.nrmse_before, predictor.nrmse(winner->fit.parameters, d.held_out_used))) {
    named = false;
    d.floor_withheld = winner->effect;
  }
  // Nothing named and the calibrated nominal model above its floor would be `unexplained`:
  // before saying so, the calibration is tried from further starts across its bands (and with
  // m free where the force balance fixed it). On other rigs the nominal fit's local minimum
  // was sometimes well above the true model (a healthy 29 mm rig: 0.0265 against the true
  // model's 0.0158 and a floor of 0.0138; issue 24's evaluation, seed 732015). A better
  // minimum only lowers every effect's gain further, so the verdict on the effects stands;
  // only `unexplained` against `none` depends on it.
  if (!named && d.nrmse_before > settings.floor_factor * d.nrmse_floor) {
    std::vector<std::pair<Calibration, FitSettings>> starts;
    FitSettings all_free = fit_settings;
    all_free.free_calibration = {true, true, true, true};
    starts.emplace_back(stated_calibration, all_free);
    for (const double beta : {0.8, 1.25}) {
      for (const double kv : {0.92, 1.08}) {
        Calibration c = catalogue;
        c.beta *= beta;
        c.Kv *= kv;
        starts.emplace_back(within_bounds(c, stated_calibration), fit_settings);
      }
    }
    for (const auto& [start, fs] : starts) {
      FitResult retry = fit_model(predictor, d.fitting_used, nullptr, start, fs);
      if (retry.cost < nominal.cost) nominal = std::move(retry);
    }
    d.nominal = nominal.parameters;
    d.nrmse_before = predictor.nrmse(nominal.parameters, d.held_out_used);
    d.calibrated = nominal.parameters.calibration;
    d.extended = nominal.parameters;
    d.nominal_at_bound = calibration_at_bound(nominal.parameters.calibration, stated_calibration);
  }
  // Forward selection: each further effect fitted jointly with the calibration and the causes
  // named so far, named only when it predicts the held-out data of that model better.
  std::vector<EffectCandidate> chosen;
  FitResult current;
  if (named) {
    EffectCandidate first = best_candidate.at(winner->effect);
    for (std::size_t i = 0; i < winner->fit.values.size(); ++i) {
      first.parameters[i].initial = winner->fit.values[i];
    }
    chosen.push_back(first);
    current = winner->fit;
    d.steps.push_back({winner->effect, predictor.nrmse(current.parameters, d.held_out_used),
                       winner->score, winner->significance, true, ""});
  }
  // A named first cause whose model leaves a calibrated value on its bound and the held-out
  // error above its floor's reach sits in a local minimum that the following steps would
  // patch with further effects (issue 24's evaluation, seed 732002: the true external leak
  // with Kv on its bound, then a supply droop and a transducer offset named next to it): it
  // is refitted from starts across the calibration's bands first. Not an effect with an onset:
  // until the onset search below its onset is the change point's, and a calibration refitted
  // to that onset compensated for it (a dead band opening at 110 s, seed 762012, named alone
  // without the retry, turned `unexplained` by the drift test with it).
  if (named && chosen.front().onset_s <= 0.0 &&
      !calibration_at_bound(current.parameters.calibration, stated_calibration).empty() &&
      predictor.nrmse(current.parameters, d.held_out_used) >
          settings.floor_factor * d.nrmse_floor) {
    std::vector<Calibration> starts = {
        within_bounds(current.parameters.calibration, stated_calibration)};
    for (const double beta : {0.8, 1.25}) {
      for (const double kv : {0.92, 1.08}) {
        Calibration c = catalogue;
        c.beta *= beta;
        c.Kv *= kv;
        starts.push_back(within_bounds(c, stated_calibration));
      }
    }
    for (const auto& start : starts) {
      FitResult retry = fit_model(predictor, d.fitting_used, &chosen.front(), start, fit_settings);
      if (retry.cost < current.cost && chosen.front().plausible(retry.values)) {
        current = std::move(retry);
        for (std::size_t i = 0; i < current.values.size(); ++i) {
          chosen.front().parameters[i].initial = current.values[i];
        }
      }
    }
  }
  const auto adds_bound = [&](const Calibration& c) {
    const auto before = calibration_at_bound(current.parameters.calibration, stated_calibration);
    for (const auto& name : calibration_at_bound(c, stated_calibration)) {
      if (std::find(before.begin(), before.end(), name) == before.end()) return true;
    }
    return false;
  };
  while (named && chosen.size() < settings.max_causes) {
    const auto current_errors = segment_errors(predictor, current.parameters, d.held_out_used);
    double current_nrmse = predictor.nrmse(current.parameters, d.held_out_used);
    // Screening against the current model (not the nominal one: a weak effect next to a
    // strong one ranks low there): every remaining candidate fitted jointly with the causes
    // named so far on the screening segments; the best few go on to the full fit.
    std::vector<std::pair<double, std::size_t>> screened_joint;
    for (std::size_t i = 0; i < library.size(); ++i) {
      const bool taken = std::any_of(chosen.begin(), chosen.end(),
                                     [&](const auto& c) { return c.effect == library[i].effect; });
      if (taken) continue;
      std::vector<EffectCandidate> parts = chosen;
      parts.push_back(library[i]);
      const EffectCandidate joint = combine(parts);
      screened_joint.emplace_back(fit_model(predictor, screening_segments, &joint,
                                            current.parameters.calibration, screening)
                                      .cost,
                                  i);
    }
    std::stable_sort(screened_joint.begin(), screened_joint.end());
    std::vector<std::size_t> next;
    for (const auto& ranked : screened_joint) {
      // Not a structured binding: Clang before 16 cannot capture one in a lambda.
      const std::size_t candidate = ranked.second;
      const bool seen = std::any_of(next.begin(), next.end(), [&](std::size_t j) {
        return library[j].effect == library[candidate].effect;
      });
      if (!seen && next.size() < settings.step_candidates) next.push_back(candidate);
    }
    // The other variants of the effects taken, in screening order: the screening on a few
    // segments can prefer the wrong channel or chamber by a hair (817201: a 3.8 ms lag of p2
    // screened behind p1's by 0.4 %; p1's full fit went to its lower bound, implausible, and
    // the lag was never named). Where a taken variant's full fit is implausible, the next
    // variant of the same effect is fitted in its place.
    std::vector<std::size_t> other_variants;
    for (const auto& ranked : screened_joint) {
      const std::size_t candidate = ranked.second;
      if (std::find(next.begin(), next.end(), candidate) != next.end()) continue;
      const bool of_next = std::any_of(next.begin(), next.end(), [&](std::size_t j) {
        return library[j].effect == library[candidate].effect;
      });
      if (of_next) other_variants.push_back(candidate);
    }
    std::optional<SelectionStep> best_step;
    EffectCandidate best_joint;
    FitResult best_fit;
    for (const std::size_t index : next) {
      // From the library's start for the new effect: its fit against the nominal model tried
      // to mimic the causes already named.
      const std::string& name = library[index].effect;
      EffectCandidate added = library[index];
      std::vector<EffectCandidate> parts = chosen;
      parts.push_back(std::move(added));
      EffectCandidate joint = combine(parts);
      FitResult fit = fit_model(predictor, d.fitting_used, &joint, current.parameters.calibration,
                                fit_settings);
      // The current calibration may sit where it soaked up the effect being added (817115: b on
      // its bound for a friction); from there the joint fit ends on further bounds. Once more
      // from the catalogue calibration, kept when it adds no bound.
      if (adds_bound(fit.parameters.calibration)) {
        FitResult retry = fit_model(predictor, d.fitting_used, &joint,
                                    within_bounds(catalogue, stated_calibration), fit_settings);
        if (!adds_bound(retry.parameters.calibration) && joint.plausible(retry.values)) {
          fit = std::move(retry);
        }
      }
      // Coulomb friction's cost has several minima along F_C: each force above the breakaway
      // changes which segments stick, and from the library's start (100 N at the paper's scale)
      // the fit stops in the nearest (817215: 276 N with b on its bound, true 368 N; 817223:
      // 160 N, true 517 N, then entrained air named for the rest). Started again at three
      // times it, the upper part of MODEL.md's 50-400 N, and from the catalogue calibration
      // (the current one may have soaked the friction up as damping); kept where its cost is
      // lower and it is plausible and adds no bound.
      if (name == "coulomb_friction" && settings.friction_restart_factor > 0.0) {
        EffectCandidate started = joint;
        started.parameters.back().initial =
            settings.friction_restart_factor * library[index].parameters.front().initial;
        FitResult retry = fit_model(predictor, d.fitting_used, &started,
                                    within_bounds(catalogue, stated_calibration), fit_settings);
        const bool fit_usable =
            joint.plausible(fit.values) && !adds_bound(fit.parameters.calibration);
        if (joint.plausible(retry.values) && !adds_bound(retry.parameters.calibration) &&
            (!fit_usable || retry.cost < fit.cost)) {
          fit = std::move(retry);
        }
      }
      if (!joint.plausible(fit.values)) {
        const auto other = std::find_if(other_variants.begin(), other_variants.end(),
                                        [&](std::size_t j) { return library[j].effect == name; });
        if (other != other_variants.end()) {
          std::vector<EffectCandidate> other_parts = chosen;
          other_parts.push_back(library[*other]);
          EffectCandidate other_joint = combine(other_parts);
          FitResult other_fit = fit_model(predictor, d.fitting_used, &other_joint,
                                          current.parameters.calibration, fit_settings);
          if (other_joint.plausible(other_fit.values)) {
            joint = std::move(other_joint);
            fit = std::move(other_fit);
          }
        }
      }
      if (!joint.plausible(fit.values)) continue;
      // A further effect that needs a calibrated value on its bound (twice MODEL.md's band
      // around the stated value) where the model without it did not is trading with the
      // calibration rather than explaining the data (a supply droop scales the valve's flow
      // as Kv does, entrained air the stiffness as beta does).
      if (adds_bound(fit.parameters.calibration)) continue;
      const auto errors = segment_errors(predictor, fit.parameters, d.held_out_used);
      SelectionStep step{name,
                         predictor.nrmse(fit.parameters, d.held_out_used),
                         held_out_gain(current_errors, errors),
                         held_out_evidence(current_errors, errors),
                         false,
                         ""};
      if (!best_step || step.score > best_step->score) {
        best_step = step;
        best_joint = std::move(joint);
        best_fit = std::move(fit);
      }
    }
    if (!best_step) break;
    // A nested comparison needs the smaller model at its best: the causes named so far are
    // refitted from where the joint fit left the calibration and their parameters. A joint
    // fit that gained only by reaching a better minimum of the current model (a sensor offset
    // and an external leak trading off, then "helped" by a valve bias) is no evidence for the
    // added effect, and its gain over the refitted model is what counts.
    {
      std::vector<EffectCandidate> restart = chosen;
      const auto shares = best_joint.split(best_fit.values);
      for (std::size_t p = 0; p < restart.size(); ++p) {
        for (std::size_t k = 0; k < restart[p].parameters.size(); ++k) {
          auto& fp = restart[p].parameters[k];
          fp.initial = std::clamp(shares[p][k], fp.lower, fp.upper);
        }
      }
      const EffectCandidate reduced = restart.size() == 1 ? restart.front() : combine(restart);
      FitResult refit = fit_model(predictor, d.fitting_used, &reduced,
                                  best_fit.parameters.calibration, fit_settings);
      if (refit.cost < current.cost && reduced.plausible(refit.values)) {
        const auto refit_shares = reduced.split(refit.values);
        for (std::size_t p = 0; p < restart.size(); ++p) {
          for (std::size_t k = 0; k < restart[p].parameters.size(); ++k) {
            restart[p].parameters[k].initial = refit_shares[p][k];
          }
        }
        chosen = std::move(restart);
        current = std::move(refit);
        const auto refit_errors = segment_errors(predictor, current.parameters, d.held_out_used);
        const auto errors = segment_errors(predictor, best_fit.parameters, d.held_out_used);
        current_nrmse = predictor.nrmse(current.parameters, d.held_out_used);
        best_step->score = held_out_gain(refit_errors, errors);
        best_step->significance = held_out_evidence(refit_errors, errors);
      }
    }
    // The same for a further effect: the model named so far at a correct model's error leaves
    // nothing to explain (seed 782013: a transducer offset named beside the true external leak
    // at 0.0119 against the true model's 0.0123).
    best_step->accepted = best_step->score >= settings.min_step_score &&
                          best_step->significance >= settings.min_step_significance &&
                          best_step->nrmse < current_nrmse &&
                          !at_floor(current_nrmse, best_step->nrmse);
    d.steps.push_back(*best_step);
    if (!best_step->accepted) break;
    chosen = parts_from_fit(best_joint, best_fit.values);
    current = std::move(best_fit);
  }

  // Forward selection keeps its first cause, the best single effect. A runner-up that lost to
  // it alone can be the better partner of the causes named after it (817111: a valve bias and
  // a supply droop on a 68 mm rig; alone, the dead band led the bias by 0.005 in score, and the
  // dead band with the droop was named at 2.1 x the true model's held-out error; 817213, a leak
  // beside a slow spool on a 48 kg rig, by 0.43 against 0.53). With two or more causes named,
  // each refined, plausible runner-up is fitted in the first cause's place beside the others
  // and kept where it predicts the held-out data better (the two models have the same causes
  // but one, so the better held-out score decides, as it decides the first cause). No window on
  // the runner-up's score: the held-out score decides, and a window only saved fits (one per
  // runner-up, where two or more causes are named at all).
  if (named && chosen.size() >= 2) {
    auto current_errors = segment_errors(predictor, current.parameters, d.held_out_used);
    for (const auto& r : d.ranking) {
      if (!r.refined || !r.plausible || r.score <= 0.0) continue;
      const bool taken = std::any_of(chosen.begin(), chosen.end(),
                                     [&](const auto& c) { return c.effect == r.effect; });
      if (taken || r.effect == "supply_ripple") continue;
      std::vector<EffectCandidate> parts = chosen;
      parts.front() = best_candidate.at(r.effect);
      for (std::size_t i = 0; i < r.fit.values.size(); ++i) {
        auto& fp = parts.front().parameters[i];
        fp.initial = std::clamp(r.fit.values[i], fp.lower, fp.upper);
      }
      EffectCandidate joint = combine(parts);
      FitResult fit = fit_model(predictor, d.fitting_used, &joint, current.parameters.calibration,
                                fit_settings);
      if (!joint.plausible(fit.values) || adds_bound(fit.parameters.calibration)) continue;
      auto errors = segment_errors(predictor, fit.parameters, d.held_out_used);
      if (held_out_gain(nominal_errors, errors) <= held_out_gain(nominal_errors, current_errors)) {
        continue;
      }
      d.steps.push_back({r.effect, predictor.nrmse(fit.parameters, d.held_out_used),
                         held_out_gain(current_errors, errors),
                         held_out_evidence(current_errors, errors), true, chosen.front().effect});
      chosen = parts_from_fit(joint, fit.values);
      current = std::move(fit);
      current_errors = std::move(errors);
    }
  }

  // An effect named with an onset: the onset searched on every segment around the proposal
  // (fitting and held-out alike: the time is not a model parameter the held-out score judges),
  // the named model's error summed over them for each trial onset. An effect that shows only
  // while the piston moves (a slower spool, a dead band) changes nothing during a hold, where
  // the sum is flat: the onset is then the middle of the flat stretch around the minimum (the
  // change is known to within it, not better).
  std::vector<std::pair<double, double>> onset_stretches(chosen.size());
  if (named) {
    for (std::size_t p = 0; p < chosen.size(); ++p) {
      auto& part = chosen[p];
      if (part.onset_s <= 0.0) continue;
      // The summed error of `trials` trial onsets evenly from `from` to `to` [s], on the
      // segments around them.
      const auto summed_errors = [&](double from, double to, int trials) {
        std::vector<Segment> near;
        for (const auto& seg : in_time) {
          const double begin = record.t[seg.begin];
          const double end = begin + static_cast<double>(seg.length) * record.dt;
          if (end > from - 0.5 && begin < to + 0.5) near.push_back(seg);
        }
        std::vector<double> onsets;
        for (int i = 0; i < trials; ++i) {
          const double onset = from + (to - from) * i / (trials - 1);
          if (onset > record.t.front() && onset < record.t.back()) onsets.push_back(onset);
        }
        const auto errors = summed_errors_at_onsets(predictor, current.parameters, near, onsets);
        std::vector<std::pair<double, double>> sums;  // onset, summed error
        for (std::size_t i = 0; i < onsets.size(); ++i) sums.emplace_back(onsets[i], errors[i]);
        return sums;
      };
      // The flat stretch around the smallest sum: [first, last] of `sums`. Flat against the
      // step into it and against the smallest sum itself: a step of orders of magnitude
      // further off would otherwise make a stretch flat whose sum still rises by half.
      const auto flat_stretch = [&](const std::vector<std::pair<double, double>>& sums) {
        std::size_t lowest = 0;
        for (std::size_t i = 1; i < sums.size(); ++i) {
          if (sums[i].second < sums[lowest].second) lowest = i;
        }
        double highest = sums[lowest].second;
        for (const auto& [onset, sum] : sums) highest = std::max(highest, sum);
        const double flat = sums[lowest].second +
                            std::min(settings.onset_flat_share * (highest - sums[lowest].second),
                                     settings.onset_flat_relative * sums[lowest].second);
        std::size_t first = lowest, last = lowest;
        while (first > 0 && sums[first - 1].second <= flat) --first;
        while (last + 1 < sums.size() && sums[last + 1].second <= flat) ++last;
        return std::pair{first, last};
      };
      // The change point is the first segment whose error is clearly up, which for an effect
      // that shows only in motion can lie several holds after the onset (seed 811031: a droop
      // from 109.0 s split at 118.5 s, the summed error still falling at the window's edge):
      // while the flat stretch reaches the window's edge, the window is widened on that side.
      // A widened window keeps the number of trials (its step grows with it, to 0.2 s at
      // +-16 s): a flat stretch is known to within its length anyway.
      const int trials =
          2 * static_cast<int>(std::lround(settings.onset_search_s / settings.onset_step_s)) + 1;
      double from = part.onset_s - settings.onset_search_s;
      double to = part.onset_s + settings.onset_search_s;
      std::vector<std::pair<double, double>> sums = summed_errors(from, to, trials);
      if (sums.empty()) continue;
      auto [first, last] = flat_stretch(sums);
      const double centre = part.onset_s;
      for (std::size_t widened = 0;
           widened < settings.onset_search_widenings + settings.onset_search_doublings; ++widened) {
        const double margin = settings.onset_step_s;
        const bool at_from = first == 0 && sums.front().first > record.t.front() + margin;
        const bool at_to = last + 1 == sums.size() && sums.back().first < record.t.back() - margin;
        if (!at_from && !at_to) break;
        const bool doubling = widened >= settings.onset_search_widenings;
        if (at_from) from -= doubling ? centre - from : 2.0 * settings.onset_search_s;
        if (at_to) to += doubling ? to - centre : 2.0 * settings.onset_search_s;
        // Doubled, the window would reach far beyond the capture, its trials wasted there.
        sums = doubling ? summed_errors(std::max(from, record.t.front()),
                                        std::min(to, record.t.back()), trials)
                        : summed_errors(from, to, trials);
        std::tie(first, last) = flat_stretch(sums);
      }
      part.onset_s = 0.5 * (sums[first].first + sums[last].first);
      onset_stretches[p] = {sums[first].first, sums[last].first};
    }
  }

  FitSettings with_errors = fit_settings;
  with_errors.uncertainties = true;
  if (named) {
    const EffectCandidate joint = chosen.size() == 1 ? chosen.front() : combine(chosen);
    const FitResult fit =
        fit_model(predictor, d.fitting_used, &joint, current.parameters.calibration, with_errors);
    const auto shares = joint.split(fit.values);
    const auto share_errors = joint.split(fit.value_errors);
    for (std::size_t p = 0; p < chosen.size(); ++p) {
      FitResult part;
      part.values = shares[p];
      part.value_errors = share_errors[p];
      d.causes.push_back({chosen[p].effect, named_values(chosen[p], part), chosen[p].onset_s,
                          onset_stretches[p].first, onset_stretches[p].second});
    }
    d.cause = d.causes.front().effect;
    d.params = d.causes.front().params;
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
  d.at_bound = calibration_at_bound(d.calibrated, stated_calibration);

  // Drift: the calibration fitted on the first and on the last third of the capture. Where it
  // moves, a named cause must hold still over the capture too, or the misfit is a changing
  // operating condition (the oil warming up) and not the constant fault the cause stands for.
  std::vector<Segment> early, late;
  const double t0 = record.t.front(), span = record.duration();
  for (const auto& seg : d.fitting_used) {
    const double position = (record.t[seg.begin] - t0) / span;
    if (position < 1.0 / 3.0) early.push_back(seg);
    if (position >= 2.0 / 3.0) late.push_back(seg);
  }
  const auto compare = [&](const std::string& name, double a, double ea, double b, double eb,
                           double relative) {
    DriftComparison c{name, a, ea, b, eb, 0.0, false};
    const double se = std::hypot(ea, eb);
    c.z = se > 0.0 ? std::abs(b - a) / se : 0.0;
    const double size = std::max(std::abs(a), std::abs(b));
    c.drifts = c.z > settings.drift_z && size > 0.0 && std::abs(b - a) > relative * size;
    d.drift.push_back(c);
    return c.drifts;
  };
  bool calibration_moves = false;
  // The nominal calibration's significant moves (late minus early; 0: none), which a named
  // model's own calibration must repeat to say that the named cause leaves the change unexplained.
  double nominal_beta_move = 0.0, nominal_b_move = 0.0;
  if (early.size() >= 3 && late.size() >= 3) {
    const FitResult fe =
        fit_model(predictor, early, nullptr, nominal.parameters.calibration, with_errors);
    const FitResult fl =
        fit_model(predictor, late, nullptr, nominal.parameters.calibration, with_errors);
    const auto& ce = fe.parameters.calibration;
    const auto& cl = fl.parameters.calibration;
    const auto& ee = fe.calibration_errors;
    const auto& el = fl.calibration_errors;
    const double rel = settings.drift_calibration_relative;
    if (compare("beta", ce.beta, ee.beta, cl.beta, el.beta, rel)) {
      calibration_moves = true;
      nominal_beta_move = cl.beta - ce.beta;
    }
    calibration_moves |= compare("Kv", ce.Kv, ee.Kv, cl.Kv, el.Kv, rel);
    if (fit_settings.free_calibration[2])
      calibration_moves |= compare("m", ce.m, ee.m, cl.m, el.m, rel);
    if (compare("b", ce.b, ee.b, cl.b, el.b, rel)) {
      calibration_moves = true;
      nominal_b_move = cl.b - ce.b;
    }
  }
  // The named model's own floor (the noise propagates differently through, say, a leaking
  // actuator); a named model at its floor leaves no misfit that could drift.
  const double nominal_floor = d.nrmse_floor;
  std::array<double, 3> extended_floor = d.channel_floor;
  if (named) {
    extended_floor =
        predictor.noise_floor(d.extended, d.held_out_used, d.noise, settings.floor_seed,
                              settings.floor_repeats, settings.floor_noise_pieces);
  }
  const double extended_reach =
      settings.floor_factor * (extended_floor[0] + extended_floor[1] + extended_floor[2]) / 3.0;
  bool cause_moves = false;
  // oil_temperature is itself the model of a change over the capture: its slope is pinned by
  // the temperature's change, which the last third of a warm-up hardly has, so it is not
  // asked to hold still (a 20 K warm-up was turned into `unexplained` that way).
  const bool models_temperature = std::any_of(
      chosen.begin(), chosen.end(), [](const auto& c) { return c.effect == "oil_temperature"; });
  if (named && calibration_moves && !models_temperature && d.nrmse_after > extended_reach) {
    // The whole named model on each third (the first cause alone would absorb the others and
    // move for that reason: two pairs were turned into `unexplained` that way); its first
    // parameter is the first cause's main one.
    const EffectCandidate joint = chosen.size() == 1 ? chosen.front() : combine(chosen);
    const FitResult fe = fit_model(predictor, early, &joint, d.calibrated, with_errors);
    const FitResult fl = fit_model(predictor, late, &joint, d.calibrated, with_errors);
    // A cause with an onset is absent from the thirds before it: its main parameter is not
    // asked to hold still, its model's calibration is (below).
    if (chosen.front().onset_s <= 0.0) {
      cause_moves = compare(joint.parameters.front().name, fe.values[0], fe.value_errors[0],
                            fl.values[0], fl.value_errors[0], settings.drift_effect_relative);
    }
    // The named model's own calibration moving as the nominal one did: the constant fault
    // named does not account for the change, the oil's properties (beta, the damping b) do
    // (warm-ups without `temp` were named sensor_offset or entrained_air, the misfit left
    // above the floor, because their main parameter held still while beta and b moved).
    const auto& ce = fe.parameters.calibration;
    const auto& cl = fl.parameters.calibration;
    const auto& ee = fe.calibration_errors;
    const auto& el = fl.calibration_errors;
    // Only a move the nominal calibration made too, in the same direction: a named model whose
    // value moves where the nominal's held still, or against it, trades that value against its
    // cause's parameters between the thirds (a friction from 57 s lowered b by 12 % while the
    // nominal b rose by 60 %; a dead band from 129 s raised beta by 23 %, the nominal's beta
    // moved by nothing significant), which is no condition changing over the capture.
    const double rel = settings.drift_calibration_relative;
    const auto repeats_nominal = [&](bool moved, double named_move, double nominal_move) {
      const bool repeated = moved && nominal_move * named_move > 0.0;
      d.drift.back().drifts = repeated;
      return repeated;
    };
    cause_moves |=
        repeats_nominal(compare("beta (named model)", ce.beta, ee.beta, cl.beta, el.beta, rel),
                        cl.beta - ce.beta, nominal_beta_move);
    cause_moves |= repeats_nominal(compare("b (named model)", ce.b, ee.b, cl.b, el.b, rel),
                                   cl.b - ce.b, nominal_b_move);
  }

  // `none` only at the floor; a misfit above it is located, and with no constant effect
  // explaining it (none named, or the named one drifting) the cause is `unexplained`.
  // `none` is judged against the nominal model's floor; the leftover misfit of a named model
  // against that model's own (the noise propagates differently through a leaking actuator).
  const double nominal_reach = settings.floor_factor * nominal_floor;
  if (named && !cause_moves) {
    d.channel_floor = extended_floor;
    d.nrmse_floor = (d.channel_floor[0] + d.channel_floor[1] + d.channel_floor[2]) / 3.0;
  }
  const double reach = settings.floor_factor * d.nrmse_floor;
  if (cause_moves) {
    d.cause = "unexplained";
    d.params.clear();
    d.causes.clear();
    d.extended = nominal.parameters;
    d.calibrated = nominal.parameters.calibration;
    d.nrmse_after = d.nrmse_before;
    d.at_bound = d.nominal_at_bound;
  } else if (!named && d.nrmse_before > nominal_reach) {
    d.cause = "unexplained";
  }
  // A calibration that moves between the thirds says "drift" only where there is a misfit to
  // explain (on clean data its optimistic errors can make it move by chance).
  d.drifts = cause_moves || (d.cause == "unexplained" && calibration_moves);
  if (d.nrmse_after > reach || d.cause == "unexplained") {
    d.unexplained = locate_misfit(predictor, d.extended, d.held_out_used, d.channel_floor);
    d.unexplained->drifts =
        d.drifts ||
        (std::abs(d.unexplained->trend_t) > 3.0 &&
         (d.unexplained->late_over_early > 2.0 || d.unexplained->late_over_early < 0.5));
  }
  // A contradicted stated value is a cause of its own, ahead of the effects judged on the
  // corrected rig (FORMATS.md); the comparison starts from the rig the user described.
  if (!d.rig_check.findings.empty()) {
    std::vector<NamedCause> rig_causes;
    for (const auto& finding : d.rig_check.findings) rig_causes.push_back(rig_cause(finding));
    d.causes.insert(d.causes.begin(), rig_causes.begin(), rig_causes.end());
    d.cause = d.causes.front().effect;
    d.params = d.causes.front().params;
    d.nrmse_before = d.nrmse_stated;
  }
  return d;
}

}  // namespace leakmon::model
