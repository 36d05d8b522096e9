// The generated filter banks against PyWavelets at test time, and their defining properties.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>

#include "dsp/dwt.hpp"
#include "dsp/wavelet.hpp"
#include "tests/dsp/pywt_oracle.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::dsp {
namespace {

TEST(Wavelet, OffersTheRequiredFamilies) {
  for (int n = 1; n <= 20; ++n) EXPECT_TRUE(has_wavelet("db" + std::to_string(n))) << n;
  for (int n = 2; n <= 20; ++n) EXPECT_TRUE(has_wavelet("sym" + std::to_string(n))) << n;
  for (int n = 1; n <= 5; ++n) EXPECT_TRUE(has_wavelet("coif" + std::to_string(n))) << n;
  EXPECT_TRUE(has_wavelet("haar"));
  EXPECT_FALSE(has_wavelet("db0"));
  EXPECT_FALSE(has_wavelet("sym1"));
}

TEST(Wavelet, UnknownNameIsRejectedWithTheName) {
  try {
    (void)wavelet("db99");
    FAIL() << "db99 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'db99'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("db1..db20"), std::string::npos) << e.what();
  }
}

TEST(Wavelet, TapsSumsAndNormsAreThoseOfOrthogonalFilters) {
  for (auto name : wavelet_names()) {
    const Wavelet& w = wavelet(name);
    const std::string family(name.substr(0, name.find_first_of("0123456789")));
    const int order = family == "haar" ? 1 : std::stoi(std::string(name.substr(family.size())));
    const std::size_t expected_taps = family == "coif" ? 6 * order : 2 * order;
    EXPECT_EQ(w.filter_length(), expected_taps) << name;
    EXPECT_EQ(w.dec_hi.size(), expected_taps) << name;
    const double lo_sum = std::accumulate(w.dec_lo.begin(), w.dec_lo.end(), 0.0);
    const double hi_sum = std::accumulate(w.dec_hi.begin(), w.dec_hi.end(), 0.0);
    const double lo_norm =
        std::inner_product(w.dec_lo.begin(), w.dec_lo.end(), w.dec_lo.begin(), 0.0);
    EXPECT_NEAR(lo_sum, std::sqrt(2.0), 1e-10) << name;
    EXPECT_NEAR(hi_sum, 0.0, 1e-10) << name;
    EXPECT_NEAR(lo_norm, 1.0, 1e-10) << name;
    // Quadrature mirror: dec_hi[i] = (-1)^(i+1) dec_lo[F-1-i]; reconstruction = time reverse.
    for (std::size_t i = 0; i < expected_taps; ++i) {
      const double sign = i % 2 == 0 ? -1.0 : 1.0;
      EXPECT_EQ(w.dec_hi[i], sign * w.dec_lo[expected_taps - 1 - i]) << name << " tap " << i;
      EXPECT_EQ(w.rec_lo[i], w.dec_lo[expected_taps - 1 - i]) << name << " tap " << i;
      EXPECT_EQ(w.rec_hi[i], w.dec_hi[expected_taps - 1 - i]) << name << " tap " << i;
    }
  }
}

TEST(Wavelet, CoefficientsEqualPyWavelets) {
  test::PywtOracle oracle("wavelet_coefficients");
  std::vector<std::size_t> requests;
  for (auto name : wavelet_names()) requests.push_back(oracle.filters(std::string(name)));
  oracle.run();
  const auto names = wavelet_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const Wavelet& w = wavelet(names[i]);
    const auto& banks = oracle.results(requests[i]);
    ASSERT_EQ(banks.size(), 4u);
    const std::span<const double> ours[] = {w.dec_lo, w.dec_hi, w.rec_lo, w.rec_hi};
    for (std::size_t b = 0; b < 4; ++b) {
      ASSERT_EQ(ours[b].size(), banks[b].size()) << names[i];
      for (std::size_t t = 0; t < banks[b].size(); ++t) {
        EXPECT_EQ(ours[b][t], banks[b][t]) << names[i] << " bank " << b << " tap " << t;
      }
    }
  }
}

TEST(Wavelet, MaxLevelEqualsPyWavelets) {
  test::PywtOracle oracle("wavelet_max_level");
  const std::size_t lengths[] = {1, 2, 14, 15, 16, 29, 30, 31, 100, 400, 401, 4096};
  const char* names[] = {"haar", "db2", "db8", "sym5", "coif5", "db20"};
  std::vector<std::size_t> requests;
  for (auto name : names) {
    for (auto n : lengths) requests.push_back(oracle.max_level(n, name));
  }
  oracle.run();
  std::size_t r = 0;
  for (auto name : names) {
    for (auto n : lengths) {
      EXPECT_EQ(dwt_max_level(n, wavelet(name).filter_length()),
                static_cast<int>(oracle.results(requests[r++]).at(0).at(0)))
          << name << " n=" << n;
    }
  }
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(Wavelet, CheckedInTablesAreWhatTheGeneratorWrites) {
  const std::string dir = test::scratch_dir("wavelet_generator");
  const std::string command = test::python() + " " + test::source_dir() +
                              "/dsp/tools/gen_wavelets.py " + dir + "/wavelet_tables.cpp > " + dir +
                              "/log.txt";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const std::string regenerated = file_text(dir + "/wavelet_tables.cpp");
  EXPECT_GT(regenerated.size(), 10000u);
  EXPECT_TRUE(regenerated == file_text(test::source_dir() + "/dsp/wavelet_tables.cpp"))
      << "dsp/wavelet_tables.cpp is not what dsp/tools/gen_wavelets.py writes: regenerate it";
}

}  // namespace
}  // namespace leakmon::dsp
