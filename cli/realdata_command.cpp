// `leakmon realdata`: the wavelet index on real actuators, the vtnsi data set
// (../shared/data/vtnsi_actuator, README there): Moog Flo-Tork rotary actuators, one file per
// stroke. Act_4 has a leaking inner seal and Act_1 is its healthy pair on the same load; Act_3
// has gear damage and Act_2 is its pair. Per stroke: the db8 level-2 detail RMS (the paper's
// index) of the pressurised port over one 400-sample window in mid-stroke and one in the hold
// after it, the stroke's length and the hold's port pressure difference. Reports, for each
// pair, the separation (AUC) of each feature and what the paper's rule "index below the
// healthy baseline" flags, so that one sees whether a leak shows and whether gear damage would
// be called a leak. Writes strokes.csv, realdata.json and realdata.md into --out.
#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/args.hpp"
#include "cli/subcommands.hpp"
#include "dsp/streaming_features.hpp"

namespace leakmon::cli {

namespace {

// The data set's README: the first ~10 samples are a sensor start-up transient.
constexpr std::size_t kStartupSamples = 10;
constexpr std::size_t kWindow = 400;     // the paper's window
constexpr std::size_t kHoldOffset = 50;  // samples after the stroke's end before the hold window
constexpr std::size_t kSmoothing = 15;   // samples in the moving average of |d angle|
constexpr double kMovingFraction = 0.2;  // of the peak smoothed angle rate: "moving"

struct Stroke {
  std::string file;
  double stroke_index = NAN;  // counts (raw 14-bit ADC)
  double hold_index = NAN;
  double stroke_samples = NAN;
  double hold_load = NAN;  // pressurised minus other port over the hold window [counts]
};

struct Unit {
  std::string folder, role;
  std::vector<Stroke> strokes;
};

// Raw columns of one stroke file; throws naming file, line and column on malformed input.
struct StrokeSignals {
  std::vector<double> angle, port1, port2;
};

StrokeSignals read_stroke(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open", path));
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(fmt::format("{}:1: empty file", path));
  std::vector<std::string> header;
  {
    std::stringstream s(line);
    std::string name;
    while (std::getline(s, name, '\t')) {
      if (!name.empty() && name.back() == '\r') name.pop_back();
      header.push_back(name);
    }
  }
  auto column = [&](std::string_view name) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) {
      throw std::runtime_error(fmt::format("{}:1: no column '{}' in the header", path, name));
    }
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::array<std::size_t, 3> wanted = {column("Angle"), column("PG_1"), column("PG_2")};
  StrokeSignals signals;
  std::size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    std::vector<std::string> fields;
    std::stringstream s(line);
    std::string field;
    while (std::getline(s, field, '\t')) fields.push_back(field);
    std::array<double, 3> values{};
    for (std::size_t k = 0; k < wanted.size(); ++k) {
      const std::size_t c = wanted[k];
      if (c >= fields.size()) {
        throw std::runtime_error(
            fmt::format("{}:{}: column {} ('{}') missing", path, line_number, c + 1, header[c]));
      }
      try {
        std::size_t used = 0;
        values[k] = std::stod(fields[c], &used);
        if (used != fields[c].size() && fields[c].substr(used) != "\r") throw std::exception();
      } catch (const std::exception&) {
        throw std::runtime_error(fmt::format("{}:{}: column {} ('{}'): '{}' is not a number", path,
                                             line_number, c + 1, header[c], fields[c]));
      }
    }
    signals.angle.push_back(values[0]);
    signals.port1.push_back(values[1]);
    signals.port2.push_back(values[2]);
  }
  return signals;
}

double detail_rms(const std::vector<double>& signal, std::size_t begin) {
  if (begin + kWindow > signal.size()) return NAN;
  dsp::FeatureParams params;
  params.window = kWindow;
  params.step = kWindow;
  const auto features =
      dsp::sliding_detail_features(std::span<const double>(signal.data() + begin, kWindow), params);
  return features.empty() || !features[0].valid ? NAN : features[0].rms;
}

// Finds the stroke (where the angle moves) and measures it.
Stroke measure(const std::string& path) {
  StrokeSignals raw = read_stroke(path);
  Stroke stroke;
  stroke.file = std::filesystem::path(path).filename().string();
  const std::size_t n = raw.angle.size();
  if (n < kStartupSamples + kWindow) return stroke;
  std::vector<double> rate(n, 0.0);
  for (std::size_t i = kStartupSamples + 1; i < n; ++i) {
    rate[i] = std::abs(raw.angle[i] - raw.angle[i - 1]);
  }
  std::vector<double> smooth(n, 0.0);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sum += rate[i];
    if (i >= kSmoothing) sum -= rate[i - kSmoothing];
    smooth[i] = sum / static_cast<double>(kSmoothing);
  }
  const double peak = *std::max_element(smooth.begin(), smooth.end());
  if (!(peak > 0.0)) return stroke;
  std::size_t first = n, last = 0;
  for (std::size_t i = kStartupSamples; i < n; ++i) {
    if (smooth[i] > kMovingFraction * peak) {
      first = std::min(first, i);
      last = i;
    }
  }
  if (first >= last) return stroke;
  double mean1 = 0.0, mean2 = 0.0;
  for (std::size_t i = first; i <= last; ++i) {
    mean1 += raw.port1[i];
    mean2 += raw.port2[i];
  }
  // Which port drives the stroke alternates with direction: the one at higher pressure.
  const auto& pressurised = mean1 >= mean2 ? raw.port1 : raw.port2;
  const auto& other = mean1 >= mean2 ? raw.port2 : raw.port1;
  const std::size_t middle = (first + last) / 2;
  stroke.stroke_samples = static_cast<double>(last - first);
  stroke.stroke_index = detail_rms(pressurised, middle >= kWindow / 2 ? middle - kWindow / 2 : 0);
  const std::size_t hold = last + kHoldOffset;
  stroke.hold_index = detail_rms(pressurised, hold);
  if (hold + kWindow <= n) {
    double load = 0.0;
    for (std::size_t i = hold; i < hold + kWindow; ++i) load += pressurised[i] - other[i];
    stroke.hold_load = load / static_cast<double>(kWindow);
  }
  return stroke;
}

Unit read_unit(const std::filesystem::path& dir, const std::string& folder,
               const std::string& role) {
  Unit unit{folder, role, {}};
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir / folder)) {
    if (entry.is_regular_file() && entry.path().extension() == ".txt") {
      files.push_back(entry.path().string());
    }
  }
  if (files.empty()) {
    throw std::runtime_error(fmt::format("{}: no stroke files (*.txt)", (dir / folder).string()));
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) unit.strokes.push_back(measure(f));
  return unit;
}

using Feature = double Stroke::*;
struct FeatureSpec {
  const char* name;
  Feature member;
};
constexpr FeatureSpec kFeatures[] = {{"stroke_index", &Stroke::stroke_index},
                                     {"hold_index", &Stroke::hold_index},
                                     {"stroke_samples", &Stroke::stroke_samples},
                                     {"hold_load", &Stroke::hold_load}};

std::vector<double> values_of(const Unit& unit, Feature member) {
  std::vector<double> v;
  for (const auto& s : unit.strokes) {
    if (!std::isnan(s.*member)) v.push_back(s.*member);
  }
  return v;
}

// P(a faulty stroke's feature > a healthy stroke's), ties counted half: 0.5 = no separation.
double auc_greater(const std::vector<double>& faulty, const std::vector<double>& healthy) {
  if (faulty.empty() || healthy.empty()) return NAN;
  double wins = 0.0;
  for (double f : faulty) {
    for (double h : healthy) wins += f > h ? 1.0 : (f == h ? 0.5 : 0.0);
  }
  return wins / (static_cast<double>(faulty.size()) * static_cast<double>(healthy.size()));
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)))];
}

double median(const std::vector<double>& v) { return quantile(v, 0.5); }

double fraction_below(const std::vector<double>& v, double threshold) {
  if (v.empty()) return NAN;
  return static_cast<double>(
             std::count_if(v.begin(), v.end(), [&](double x) { return x < threshold; })) /
         static_cast<double>(v.size());
}

}  // namespace

int run_realdata(int argc, char** argv) {
  ArgParser args("realdata",
                 "The paper's index on the vtnsi real-actuator data set: per-stroke features,\n"
                 "separation (AUC) of the leaking unit from its healthy pair and of the gear-\n"
                 "damaged unit from its pair, and what the paper's index-drop rule flags.");
  args.option("data", "DIR", "the data set (folders Act_1 .. Act_4_seal_defect)", std::nullopt,
              true)
      .option("out", "DIR", "output directory", std::nullopt, true)
      .option("baseline-quantile", "Q",
              "the paper's rule flags strokes whose index is below this quantile of the "
              "healthy pair's",
              "0.05");
  if (!args.parse(argc, argv)) return 0;
  const std::filesystem::path data = args.get("data");
  const std::filesystem::path out = args.get("out");
  const double q = args.get_double("baseline-quantile");
  if (!(q > 0.0 && q < 1.0)) throw UsageError("option '--baseline-quantile': must be in (0, 1)");
  if (!std::filesystem::is_directory(data)) {
    throw std::runtime_error(fmt::format("{}: not a directory", data.string()));
  }
  std::filesystem::create_directories(out);

  struct Pair {
    const char* label;
    Unit faulty, healthy;
  };
  std::vector<Pair> pairs;
  pairs.push_back({"seal leak (Act_4) vs healthy Act_1, butterfly-valve load",
                   read_unit(data, "Act_4_seal_defect", "seal defect"),
                   read_unit(data, "Act_1", "healthy")});
  pairs.push_back({"gear damage (Act_3) vs healthy Act_2, ball-valve load",
                   read_unit(data, "Act_3_gear_damage", "gear damage"),
                   read_unit(data, "Act_2", "healthy")});

  {
    auto csv = fmt::output_file((out / "strokes.csv").string());
    csv.print("unit,file,stroke_index,hold_index,stroke_samples,hold_load\n");
    for (const auto& pair : pairs) {
      for (const Unit* unit : {&pair.faulty, &pair.healthy}) {
        for (const auto& s : unit->strokes) {
          csv.print("{},\"{}\",{},{},{},{}\n", unit->folder, s.file, s.stroke_index, s.hold_index,
                    s.stroke_samples, s.hold_load);
        }
      }
    }
  }

  auto json = fmt::output_file((out / "realdata.json").string());
  std::string md;
  json.print("{{\"baseline_quantile\": {}, \"pairs\": [\n", q);
  md += fmt::format(
      "| pair | feature | median faulty | median healthy | AUC (faulty > healthy) |\n"
      "|---|---|---|---|---|\n");
  std::string rule_rows;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const Pair& pair = pairs[p];
    json.print(
        "  {{\"pair\": \"{}\", \"faulty\": \"{}\", \"healthy\": \"{}\", \"strokes\": [{}, {}], "
        "\"features\": {{",
        pair.label, pair.faulty.folder, pair.healthy.folder, pair.faulty.strokes.size(),
        pair.healthy.strokes.size());
    for (std::size_t k = 0; k < std::size(kFeatures); ++k) {
      const auto f = values_of(pair.faulty, kFeatures[k].member);
      const auto h = values_of(pair.healthy, kFeatures[k].member);
      const double auc = auc_greater(f, h);
      json.print(
          "{}\"{}\": {{\"median_faulty\": {:.6g}, \"median_healthy\": {:.6g}, "
          "\"auc_greater\": {:.4f}, \"n\": [{}, {}]}}",
          k ? ", " : "", kFeatures[k].name, median(f), median(h), auc, f.size(), h.size());
      md += fmt::format("| {} | {} | {:.4g} | {:.4g} | {:.2f} |\n", pair.label, kFeatures[k].name,
                        median(f), median(h), auc);
    }
    // The paper's rule with a learned baseline: a stroke is "leaking" when its index is below
    // the q-quantile of the healthy pair's strokes.
    const auto healthy_index = values_of(pair.healthy, &Stroke::stroke_index);
    const auto faulty_index = values_of(pair.faulty, &Stroke::stroke_index);
    const double baseline = quantile(healthy_index, q);
    const double flagged = fraction_below(faulty_index, baseline);
    json.print(
        "}}, \"paper_rule\": {{\"baseline\": {:.6g}, \"flagged_faulty\": {:.4f}, "
        "\"flagged_healthy\": {:.4f}}}}}{}\n",
        baseline, flagged, fraction_below(healthy_index, baseline),
        p + 1 < pairs.size() ? "," : "");
    rule_rows += fmt::format("| {} | {:.4g} | {:.0f} % | {:.0f} % |\n", pair.label, baseline,
                             100.0 * flagged, 100.0 * fraction_below(healthy_index, baseline));
  }
  json.print("]}}\n");
  md += fmt::format(
      "\nThe paper's rule (stroke index below the {:.0f} % quantile of the healthy pair):\n\n"
      "| pair | baseline [counts] | faulty strokes flagged | healthy strokes flagged |\n"
      "|---|---|---|---|\n{}",
      100.0 * q, rule_rows);
  json.close();
  auto md_file = fmt::output_file((out / "realdata.md").string());
  md_file.print("{}", md);
  md_file.close();
  fmt::print("{}", md);
  return 0;
}

}  // namespace leakmon::cli
