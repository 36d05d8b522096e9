#include "model/measured_record.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
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
