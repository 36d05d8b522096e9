#include "tests/dsp/pywt_oracle.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tests/support/paths.hpp"

namespace leakmon::test {
namespace {

std::string numbers(std::span<const double> values) {
  std::string line;
  for (double v : values) line += fmt::format("{:.17g} ", v);
  return line;
}

}  // namespace

PywtOracle::PywtOracle(const std::string& scratch_name) : dir_(scratch_dir(scratch_name)) {}

std::size_t PywtOracle::filters(const std::string& wavelet) {
  requests_ += fmt::format("filters {}\n", wavelet);
  return count_++;
}

std::size_t PywtOracle::max_level(std::size_t length, const std::string& wavelet) {
  requests_ += fmt::format("max_level {} {}\n", length, wavelet);
  return count_++;
}

std::size_t PywtOracle::wavedec(std::span<const double> signal, const std::string& wavelet,
                                const std::string& mode, int level) {
  requests_ += fmt::format("wavedec {} {} {}\n{}\n", wavelet, mode, level, numbers(signal));
  return count_++;
}

std::size_t PywtOracle::sliding(std::span<const double> signal, const std::string& wavelet,
                                const std::string& mode, int level, std::size_t window,
                                std::size_t step) {
  requests_ += fmt::format("sliding {} {} {} {} {}\n{}\n", wavelet, mode, level, window, step,
                           numbers(signal));
  return count_++;
}

void PywtOracle::run() {
  const std::string request_path = dir_ + "/request.txt";
  const std::string result_path = dir_ + "/result.txt";
  std::ofstream(request_path) << requests_;
  const std::string script = source_dir() + "/tests/dsp/pywt_oracle.py";
  const std::string command =
      fmt::format("'{}' '{}' '{}' '{}'", python(), script, request_path, result_path);
  if (std::system(command.c_str()) != 0) {
    throw std::runtime_error("pywt oracle failed: " + command);
  }
  std::ifstream in(result_path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.starts_with("result ")) {
      results_.emplace_back();
      continue;
    }
    if (results_.empty()) throw std::runtime_error("pywt oracle: output without 'result' line");
    std::istringstream words(line);
    std::vector<double> values;
    std::string word;
    while (words >> word) values.push_back(std::strtod(word.c_str(), nullptr));  // parses "nan"
    results_.back().push_back(std::move(values));
  }
  if (results_.size() != count_) {
    throw std::runtime_error(
        fmt::format("pywt oracle: {} results for {} requests", results_.size(), count_));
  }
}

const std::vector<std::vector<double>>& PywtOracle::results(std::size_t request) const {
  return results_.at(request);
}

double relative_error(std::span<const double> actual, std::span<const double> expected) {
  if (actual.size() != expected.size()) return INFINITY;
  double scale = 0.0;
  double worst = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    scale = std::max(scale, std::abs(expected[i]));
    worst = std::max(worst, std::abs(actual[i] - expected[i]));
  }
  return scale > 0.0 ? worst / scale : worst;
}

}  // namespace leakmon::test
