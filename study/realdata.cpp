#include "study/realdata.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <cmath>

namespace leakmon::study {
namespace {

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

std::vector<PairSpec> vtnsi_layout() {
  return {
      {"seal leak (Act_4) vs healthy Act_1, butterfly-valve load",
       {"Act_4_seal_defect", "seal defect"},
       {"Act_1", "healthy"}},
      {"gear damage (Act_3) vs healthy Act_2, ball-valve load",
       {"Act_3_gear_damage", "gear damage"},
       {"Act_2", "healthy"}},
  };
}

Unit read_unit(const std::filesystem::path& data, const UnitSpec& spec) {
  Unit unit{spec.folder, spec.role, {}};
  for (const auto& f : stroke_files(data / spec.folder)) unit.strokes.push_back(measure_stroke(f));
  return unit;
}

double auc_greater(const std::vector<double>& faulty, const std::vector<double>& healthy) {
  if (faulty.empty() || healthy.empty()) return NAN;
  double wins = 0.0;
  for (double f : faulty) {
    for (double h : healthy) wins += f > h ? 1.0 : (f == h ? 0.5 : 0.0);
  }
  return wins / (static_cast<double>(faulty.size()) * static_cast<double>(healthy.size()));
}

RealdataResult analyse_realdata(const std::filesystem::path& data,
                                const std::vector<PairSpec>& layout, double baseline_quantile) {
  RealdataResult result;
  result.baseline_quantile = baseline_quantile;
  for (const PairSpec& spec : layout) {
    PairResult pair;
    pair.label = spec.label;
    pair.faulty = read_unit(data, spec.faulty);
    pair.healthy = read_unit(data, spec.healthy);
    result.pairs.push_back(std::move(pair));
  }
  for (PairResult& pair : result.pairs) {
    for (const FeatureSpec& feature : kFeatures) {
      const auto f = values_of(pair.faulty, feature.member);
      const auto h = values_of(pair.healthy, feature.member);
      pair.features.push_back(
          {feature.name, median(f), median(h), auc_greater(f, h), f.size(), h.size()});
    }
    const auto healthy_index = values_of(pair.healthy, &Stroke::stroke_index);
    const auto faulty_index = values_of(pair.faulty, &Stroke::stroke_index);
    pair.baseline = quantile(healthy_index, baseline_quantile);
    pair.flagged_faulty = fraction_below(faulty_index, pair.baseline);
    pair.flagged_healthy = fraction_below(healthy_index, pair.baseline);
  }
  return result;
}

void write_strokes_csv(const std::filesystem::path& path, const RealdataResult& result) {
  auto csv = fmt::output_file(path.string());
  csv.print("unit,file,stroke_index,hold_index,stroke_samples,hold_load\n");
  for (const auto& pair : result.pairs) {
    for (const Unit* unit : {&pair.faulty, &pair.healthy}) {
      for (const auto& s : unit->strokes) {
        csv.print("{},\"{}\",{},{},{},{}\n", unit->folder, s.file, s.stroke_index, s.hold_index,
                  s.stroke_samples, s.hold_load);
      }
    }
  }
}

void write_realdata_json(const std::filesystem::path& path, const RealdataResult& result) {
  auto json = fmt::output_file(path.string());
  json.print("{{\"baseline_quantile\": {}, \"pairs\": [\n", result.baseline_quantile);
  for (std::size_t p = 0; p < result.pairs.size(); ++p) {
    const PairResult& pair = result.pairs[p];
    json.print(
        "  {{\"pair\": \"{}\", \"faulty\": \"{}\", \"healthy\": \"{}\", \"strokes\": [{}, {}], "
        "\"features\": {{",
        pair.label, pair.faulty.folder, pair.healthy.folder, pair.faulty.strokes.size(),
        pair.healthy.strokes.size());
    for (std::size_t k = 0; k < pair.features.size(); ++k) {
      const FeatureComparison& f = pair.features[k];
      json.print(
          "{}\"{}\": {{\"median_faulty\": {:.6g}, \"median_healthy\": {:.6g}, "
          "\"auc_greater\": {:.4f}, \"n\": [{}, {}]}}",
          k ? ", " : "", f.name, f.median_faulty, f.median_healthy, f.auc_greater, f.n_faulty,
          f.n_healthy);
    }
    json.print(
        "}}, \"paper_rule\": {{\"baseline\": {:.6g}, \"flagged_faulty\": {:.4f}, "
        "\"flagged_healthy\": {:.4f}}}}}{}\n",
        pair.baseline, pair.flagged_faulty, pair.flagged_healthy,
        p + 1 < result.pairs.size() ? "," : "");
  }
  json.print("]}}\n");
}

std::string realdata_markdown(const RealdataResult& result) {
  std::string md =
      "| pair | feature | median faulty | median healthy | AUC (faulty > healthy) |\n"
      "|---|---|---|---|---|\n";
  std::string rule_rows;
  for (const PairResult& pair : result.pairs) {
    for (const FeatureComparison& f : pair.features) {
      md += fmt::format("| {} | {} | {:.4g} | {:.4g} | {:.2f} |\n", pair.label, f.name,
                        f.median_faulty, f.median_healthy, f.auc_greater);
    }
    rule_rows += fmt::format("| {} | {:.4g} | {:.0f} % | {:.0f} % |\n", pair.label, pair.baseline,
                             100.0 * pair.flagged_faulty, 100.0 * pair.flagged_healthy);
  }
  md += fmt::format(
      "\nThe paper's rule (stroke index below the {:.0f} % quantile of the healthy pair):\n\n"
      "| pair | baseline [counts] | faulty strokes flagged | healthy strokes flagged |\n"
      "|---|---|---|---|\n{}",
      100.0 * result.baseline_quantile, rule_rows);
  return md;
}

}  // namespace leakmon::study
