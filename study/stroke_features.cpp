#include "study/stroke_features.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "dsp/streaming_features.hpp"

namespace leakmon::study {
namespace {

// The data set's README: the first ~10 samples are a sensor start-up transient.
constexpr std::size_t kStartupSamples = 10;
constexpr std::size_t kWindow = 400;     // the paper's window
constexpr std::size_t kHoldOffset = 50;  // samples after the stroke's end before the hold window
constexpr std::size_t kSmoothing = 15;   // samples in the moving average of |d angle|
constexpr double kMovingFraction = 0.2;  // of the peak smoothed angle rate: "moving"

double detail_rms(const std::vector<double>& signal, std::size_t begin) {
  if (begin + kWindow > signal.size()) return NAN;
  dsp::FeatureParams params;
  params.window = kWindow;
  params.step = kWindow;
  const auto features =
      dsp::sliding_detail_features(std::span<const double>(signal.data() + begin, kWindow), params);
  return features.empty() || !features[0].valid ? NAN : features[0].rms;
}

}  // namespace

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

Stroke measure_stroke(const std::string& path) {
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

std::vector<std::string> stroke_files(const std::filesystem::path& folder) {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().extension() == ".txt") {
      files.push_back(entry.path().string());
    }
  }
  if (files.empty()) {
    throw std::runtime_error(fmt::format("{}: no stroke files (*.txt)", folder.string()));
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace leakmon::study
