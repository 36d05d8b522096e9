// Runs tests/dsp/pywt_oracle.py (PyWavelets, under Debian's /usr/bin/python3) on a batch of
// requests, exchanging plain-text files in the test's scratch directory.
#pragma once

#include <span>
#include <string>
#include <vector>

namespace leakmon::test {

class PywtOracle {
 public:
  explicit PywtOracle(const std::string& scratch_name);

  // Each request returns its index; results(index) holds its output lines, parsed as numbers.
  std::size_t filters(const std::string& wavelet);
  std::size_t max_level(std::size_t length, const std::string& wavelet);
  std::size_t wavedec(std::span<const double> signal, const std::string& wavelet,
                      const std::string& mode, int level);
  std::size_t sliding(std::span<const double> signal, const std::string& wavelet,
                      const std::string& mode, int level, std::size_t window, std::size_t step);

  void run();  // throws std::runtime_error when the script fails
  const std::vector<std::vector<double>>& results(std::size_t request) const;

 private:
  std::string dir_;
  std::string requests_;
  std::size_t count_ = 0;
  std::vector<std::vector<std::vector<double>>> results_;
};

// max |a - b| / max |b| (or the absolute difference when b is all zeros); sizes must match.
double relative_error(std::span<const double> actual, std::span<const double> expected);

}  // namespace leakmon::test
