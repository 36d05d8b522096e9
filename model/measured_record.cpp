#include "model/measured_record.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>

namespace leakmon::model {
namespace {

constexpr std::array<std::string_view, 5> kRequired = {"t", "u", "x", "p1", "p2"};

// Where a row came from, for error messages: a file line, or a row number in memory.
struct RowOrigin {
  std::vector<std::size_t> lines;  // empty: rows counted from 1
  std::string where(std::size_t row) const {
    return lines.empty() ? fmt::format("row {}", row + 1) : fmt::format("{}", lines[row]);
  }
};

// Marks the samples where a pressure sits at its range end invalid (MeasuredRecord::Censored).
void censor_range_end(MeasuredRecord& rec, std::string_view name,
                      const std::vector<double>& channel, const RowOrigin& origin,
                      const RecordRequirements& req) {
  const std::size_t n = rec.size();
  // One pass keeping the two largest distinct readings and how often each occurs.
  double top = -std::numeric_limits<double>::infinity();
  double below = -std::numeric_limits<double>::infinity();
  std::size_t at_top = 0;
  std::size_t at_below = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!rec.valid[i]) continue;
    const double v = channel[i];
    if (v == top) {
      ++at_top;
    } else if (v > top) {
      below = top;
      at_below = at_top;
      top = v;
      at_top = 1;
    } else if (v == below) {
      ++at_below;
    } else if (v > below) {
      below = v;
      at_below = 1;
    }
  }
  // A channel reading one value throughout shows no range end, only a constant level.
  if (!std::isfinite(below) || at_top < req.pinned_min_samples ||
      static_cast<double>(at_top) <
          req.pinned_ratio * static_cast<double>(std::max<std::size_t>(at_below, 1))) {
    return;
  }
  MeasuredRecord::Censored censored{
      MeasuredRecord::Censored::Reason::range_end, std::string(name), top, at_top, 0, "", 0.0};
  for (std::size_t i = 0; i < n; ++i) {
    if (!rec.valid[i] || channel[i] != top) continue;
    if (censored.first.empty()) censored.first = origin.where(i);
    rec.valid[i] = false;
  }
  rec.censored.push_back(std::move(censored));
}

// Replaces isolated spikes by their neighbours' median (RecordRequirements::spike_scales).
void clean_spikes(MeasuredRecord& rec, std::string_view name, std::vector<double>& channel,
                  const RowOrigin& origin, const RecordRequirements& req) {
  const std::size_t n = rec.size();
  if (n < 5) return;
  struct Candidate {
    std::size_t row;
    double median, deviation, spread;
  };
  std::vector<Candidate> candidates;
  std::vector<double> deviations;
  for (std::size_t k = 2; k + 2 < n; ++k) {
    if (!(rec.valid[k - 2] && rec.valid[k - 1] && rec.valid[k] && rec.valid[k + 1] &&
          rec.valid[k + 2])) {
      continue;
    }
    std::array<double, 4> around = {channel[k - 2], channel[k - 1], channel[k + 1], channel[k + 2]};
    std::sort(around.begin(), around.end());
    // The lower median: a reading the channel took, so a replaced spike adds no value of its
    // own (censor_range_end counts how often each value occurs).
    const double median = around[1];
    candidates.push_back({k, median, channel[k] - median, around[3] - around[0]});
    deviations.push_back(std::abs(channel[k] - median));
  }
  if (deviations.empty()) return;
  const auto mid = deviations.begin() + static_cast<std::ptrdiff_t>(deviations.size() / 2);
  std::nth_element(deviations.begin(), mid, deviations.end());
  // The noise's scale; on a quantised channel at rest the median deviation can be 0, so at
  // least the smallest step the channel takes.
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < n; ++k) {
    const double d = std::abs(channel[k] - channel[k - 1]);
    if (d > 0.0 && std::isfinite(d)) step = std::min(step, d);
  }
  const double scale = std::max(1.4826 * *mid, std::isfinite(step) ? step : 0.0);
  if (!(scale > 0.0)) return;
  std::vector<Candidate> spikes;
  for (const auto& c : candidates) {
    if (std::abs(c.deviation) > req.spike_scales * scale &&
        std::abs(c.deviation) > req.spike_spread * c.spread) {
      spikes.push_back(c);
    }
  }
  if (spikes.empty() ||
      static_cast<double>(spikes.size()) > req.max_spikes_per_min * rec.duration() / 60.0) {
    return;
  }
  MeasuredRecord::Censored cleaned{MeasuredRecord::Censored::Reason::spikes,
                                   std::string(name),
                                   0.0,
                                   spikes.size(),
                                   spikes.size(),
                                   origin.where(spikes[0].row),
                                   0.0};
  for (const auto& c : spikes) {
    channel[c.row] = c.median;
    if (std::abs(c.deviation) > std::abs(cleaned.value)) cleaned.value = c.deviation;
  }
  rec.censored.push_back(std::move(cleaned));
}

// Marks runs of one exact value lasting `held_min_s` or longer invalid.
void censor_held(MeasuredRecord& rec, std::string_view name, const std::vector<double>& channel,
                 const RowOrigin& origin, const RecordRequirements& req) {
  const std::size_t n = rec.size();
  const auto min_run = static_cast<std::size_t>(std::ceil(req.held_min_s / rec.dt));
  MeasuredRecord::Censored censored{
      MeasuredRecord::Censored::Reason::held, std::string(name), 0.0, 0, 0, "", req.held_min_s};
  std::size_t begin = 0;
  for (std::size_t i = 1; i <= n; ++i) {
    if (i < n && channel[i] == channel[begin]) continue;
    if (i - begin >= min_run && std::isfinite(channel[begin])) {
      if (censored.runs++ == 0) {
        censored.value = channel[begin];
        censored.first = origin.where(begin);
      }
      for (std::size_t k = begin; k < i; ++k) {
        censored.samples += rec.valid[k];
        rec.valid[k] = false;
      }
    }
    begin = i;
  }
  if (censored.runs > 0) rec.censored.push_back(std::move(censored));
}

MeasuredRecord vet(MeasuredRecord rec, const RowOrigin& origin, const RecordRequirements& req) {
  const std::size_t n = rec.size();
  if (n < 3) {
    throw ModelCheckError(
        fmt::format("{}: capture holds {} samples; the model check needs at "
                    "least {} s of data",
                    rec.source, n, req.min_duration_s));
  }
  // The sample period is the median step; every step must match it (regular sampling).
  std::vector<double> steps(n - 1);
  for (std::size_t i = 1; i < n; ++i) steps[i - 1] = rec.t[i] - rec.t[i - 1];
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  rec.dt = sorted[sorted.size() / 2];
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (std::abs(steps[i] - rec.dt) > req.rate_tolerance * rec.dt) {
      throw ModelCheckError(fmt::format(
          "{}:{}: column t: step {} s differs from the sample period {} s; the model check "
          "needs regularly sampled data (mark missing samples as empty fields instead)",
          rec.source, origin.where(i + 1), steps[i], rec.dt));
    }
  }
  if (rec.duration() < req.min_duration_s) {
    throw ModelCheckError(fmt::format(
        "{}: capture is too short: {:.3f} s; the model check needs at least {} s to fit the "
        "model and score it on held-out data",
        rec.source, rec.duration(), req.min_duration_s));
  }
  rec.valid.assign(n, true);
  std::size_t missing = 0;
  std::optional<std::pair<std::size_t, std::string_view>> first_gap;
  const std::array<const std::vector<double>*, 4> channels = {&rec.u, &rec.x, &rec.p1, &rec.p2};
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < channels.size(); ++c) {
      if (std::isfinite((*channels[c])[i])) continue;
      rec.valid[i] = false;
      if (!first_gap) first_gap = {i, kRequired[c + 1]};
    }
    if (!rec.valid[i]) ++missing;
  }
  const double gap_fraction = static_cast<double>(missing) / static_cast<double>(n);
  if (gap_fraction > req.max_gap_fraction) {
    throw ModelCheckError(fmt::format(
        "{}: {:.1f} % of the samples have gaps (first at line {}, column {}); the model check "
        "accepts at most {:.1f} %",
        rec.source, 100.0 * gap_fraction, origin.where(first_gap->first), first_gap->second,
        100.0 * req.max_gap_fraction));
  }
  clean_spikes(rec, "x", rec.x, origin, req);
  clean_spikes(rec, "p1", rec.p1, origin, req);
  clean_spikes(rec, "p2", rec.p2, origin, req);
  censor_held(rec, "x", rec.x, origin, req);
  censor_held(rec, "p1", rec.p1, origin, req);
  censor_held(rec, "p2", rec.p2, origin, req);
  censor_range_end(rec, "p1", rec.p1, origin, req);
  censor_range_end(rec, "p2", rec.p2, origin, req);
  std::size_t censored = 0;
  // Spikes were replaced, not left out.
  const auto left_out = [](const MeasuredRecord::Censored& c) {
    return c.reason == MeasuredRecord::Censored::Reason::spikes ? std::size_t{0} : c.samples;
  };
  for (const auto& c : rec.censored) censored += left_out(c);
  const double censored_fraction = static_cast<double>(censored) / static_cast<double>(n);
  if (censored_fraction > req.max_censored_fraction) {
    const auto& worst =
        *std::max_element(rec.censored.begin(), rec.censored.end(),
                          [&](const auto& a, const auto& b) { return left_out(a) < left_out(b); });
    const bool range_end = worst.reason == MeasuredRecord::Censored::Reason::range_end;
    throw ModelCheckError(fmt::format(
        "{}:{}: column {} {} {} on {} samples{}; {:.1f} % of the capture is left out as "
        "transducer faults or clipping and the model check accepts at most {:.1f} %",
        rec.source, worst.first, worst.channel,
        range_end ? "sits at its largest reading (a transducer's range end),"
                  : "holds one exact value (a frozen, dropped-out or saturated transducer),",
        worst.value, worst.samples,
        range_end ? "" : fmt::format(" in {} run(s) of {} s or more", worst.runs, req.held_min_s),
        100.0 * censored_fraction, 100.0 * req.max_censored_fraction));
  }
  return rec;
}

void require_columns(const std::vector<std::string>& columns, const std::string& source) {
  std::string missing;
  for (auto name : kRequired) {
    bool found = false;
    for (const auto& c : columns) found = found || c == name;
    if (!found) missing += fmt::format("{}'{}'", missing.empty() ? "" : ", ", name);
  }
  if (!missing.empty()) {
    std::string header;
    for (const auto& c : columns) header += (header.empty() ? "" : ",") + c;
    throw ModelCheckError(
        fmt::format("{}: header '{}' lacks column(s) {}; the model check needs "
                    "t,u,x,p1,p2",
                    source, header, missing));
  }
}

std::string controller_from(const capture::Metadata& metadata) {
  for (const auto& [key, value] : metadata) {
    if (key != "controller") continue;
    if (value.find("fault") != std::string::npos) return "fault_tolerant";
    if (value.find("basic") != std::string::npos) return "basic";
  }
  return "";
}

}  // namespace

MeasuredRecord read_measured_record(const std::string& path, const RecordRequirements& req) {
  capture::CaptureReader reader(path);
  require_columns(reader.columns(), path);
  const auto col = [&](std::string_view name) { return *reader.column_index(name); };
  const auto xref = reader.column_index("xref");
  const auto ps = reader.column_index("ps");
  const auto temp = reader.column_index("temp");
  MeasuredRecord rec;
  rec.source = path;
  rec.controller = controller_from(reader.metadata());
  RowOrigin origin;
  std::vector<double> row(reader.columns().size());
  while (reader.next(row)) {
    rec.t.push_back(row[col("t")]);
    rec.u.push_back(row[col("u")]);
    rec.x.push_back(row[col("x")]);
    rec.p1.push_back(row[col("p1")]);
    rec.p2.push_back(row[col("p2")]);
    if (xref) rec.xref.push_back(row[*xref]);
    if (ps) rec.ps.push_back(row[*ps]);
    if (temp) rec.temp.push_back(row[*temp]);
    origin.lines.push_back(reader.line_number());
  }
  return vet(std::move(rec), origin, req);
}

MeasuredRecord measured_record(const capture::Capture& capture, const RecordRequirements& req) {
  require_columns(capture.columns, capture.path);
  MeasuredRecord rec;
  rec.source = capture.path;
  rec.controller = controller_from(capture.metadata);
  rec.t = capture.column("t");
  rec.u = capture.column("u");
  rec.x = capture.column("x");
  rec.p1 = capture.column("p1");
  rec.p2 = capture.column("p2");
  if (capture.has("xref")) rec.xref = capture.column("xref");
  if (capture.has("ps")) rec.ps = capture.column("ps");
  if (capture.has("temp")) rec.temp = capture.column("temp");
  return vet(std::move(rec), RowOrigin{}, req);
}

}  // namespace leakmon::model
