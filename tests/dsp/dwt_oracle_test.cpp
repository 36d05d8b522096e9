// pywt.wavedec against dsp::wavedec over random signals, several lengths, all nine modes,
// several wavelets and levels: same lengths, coefficients within 1e-12 relative.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

#include "dsp/dwt.hpp"
#include "tests/dsp/pywt_oracle.hpp"

namespace leakmon::dsp {
namespace {

constexpr Mode kModes[] = {Mode::zero,          Mode::constant,      Mode::symmetric,
                           Mode::reflect,       Mode::periodic,      Mode::smooth,
                           Mode::periodization, Mode::antisymmetric, Mode::antireflect};

std::vector<double> random_signal(std::size_t n, std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(n);
  for (auto& v : x) v = 5.0 + normal(rng);  // an offset, like a pressure around its mean
  return x;
}

struct Case {
  std::string wavelet;
  Mode mode;
  int level;
  std::vector<double> signal;
  std::size_t request;
};

// Every array of every case within 1e-12 relative of PyWavelets' (after oracle.run()).
void expect_wavedec_matches(const std::vector<Case>& cases, const test::PywtOracle& oracle) {
  for (const Case& c : cases) {
    const auto ours = wavedec(c.signal, wavelet(c.wavelet), c.mode, c.level);
    const auto& theirs = oracle.results(c.request);
    const std::string label = c.wavelet + " " + std::string(mode_name(c.mode)) +
                              " n=" + std::to_string(c.signal.size()) + " level " +
                              std::to_string(c.level);
    ASSERT_EQ(ours.size(), theirs.size()) << label;
    for (std::size_t a = 0; a < ours.size(); ++a) {
      ASSERT_EQ(ours[a].size(), theirs[a].size()) << label << " array " << a;
      EXPECT_LE(test::relative_error(ours[a], theirs[a]), 1e-12) << label << " array " << a;
    }
  }
}

TEST(DwtOracle, WavedecMatchesPyWavelets) {
  std::mt19937_64 rng(20240611);
  test::PywtOracle oracle("dwt_oracle_wavedec");
  std::vector<Case> cases;
  const char* wavelets[] = {"haar", "db2", "db8", "sym5", "coif3", "db20"};
  const std::size_t lengths[] = {5, 16, 17, 33, 64, 101, 400, 401};
  for (const char* name : wavelets) {
    const std::size_t taps = wavelet(name).filter_length();
    for (std::size_t n : lengths) {
      const int max_level = dwt_max_level(n, taps);
      for (Mode mode : kModes) {
        // Level 1 always (filters longer than the signal included: repeated reflections),
        // then 2 and the maximum where they are meaningful.
        for (int level : {1, 2, max_level}) {
          if (level < 1 || (level > 1 && level > max_level)) continue;
          Case c{name, mode, level, random_signal(n, rng), 0};
          c.request = oracle.wavedec(c.signal, name, std::string(mode_name(mode)), level);
          cases.push_back(std::move(c));
        }
      }
    }
  }
  oracle.run();
  ASSERT_GT(cases.size(), 500u);
  expect_wavedec_matches(cases, oracle);
}

// A large level with little variation (MODEL.md's noise-free plant: ~8.65 MPa +- 100 Pa): each
// detail coefficient is then the difference of sums ~1e5 times larger than itself, so its last
// bits depend on the order in which its taps are summed. PyWavelets adds, at the right end of
// the folding modes, the extension taps first (Decimation::reversed_taps); in ascending order
// alone the detail coefficients there were off by up to ~1e-11 of the array's largest.
TEST(DwtOracle, LowNoiseOnALargeLevelMatchesPyWaveletsCoefficientByCoefficient) {
  std::mt19937_64 rng(8650000);
  std::normal_distribution<double> normal(0.0, 1.0);
  test::PywtOracle oracle("dwt_oracle_low_noise");
  std::vector<Case> cases;
  for (const char* name : {"db8", "sym5", "db20", "haar"}) {
    const std::size_t taps = wavelet(name).filter_length();
    for (std::size_t n : {std::size_t{33}, std::size_t{207}, std::size_t{400}, std::size_t{401}}) {
      for (const double noise : {100.0, 1.0}) {
        for (Mode mode : kModes) {
          for (int level : {1, std::max(2, dwt_max_level(n, taps))}) {
            std::vector<double> x(n);
            double drift = 8.65e6;
            for (auto& v : x) {
              drift += 0.4 * noise * normal(rng);
              v = drift + noise * normal(rng);
            }
            Case c{name, mode, level, std::move(x), 0};
            c.request = oracle.wavedec(c.signal, name, std::string(mode_name(mode)), level);
            cases.push_back(std::move(c));
          }
        }
      }
    }
  }
  oracle.run();
  expect_wavedec_matches(cases, oracle);
}

TEST(Dwt, CoeffLenFollowsPyWavelets) {
  EXPECT_EQ(dwt_coeff_len(400, 16, Mode::symmetric), 207u);
  EXPECT_EQ(dwt_coeff_len(207, 16, Mode::symmetric), 111u);
  EXPECT_EQ(dwt_coeff_len(401, 16, Mode::periodization), 201u);
  EXPECT_EQ(dwt_coeff_len(5, 16, Mode::zero), 10u);
}

TEST(Dwt, RejectsNegativeLevelAndEmptySignal) {
  std::vector<double> x(32, 1.0);
  EXPECT_THROW(wavedec(x, wavelet("db2"), Mode::symmetric, -1), std::invalid_argument);
  EXPECT_THROW(wavedec(std::span<const double>(), wavelet("db2"), Mode::symmetric, 1),
               std::invalid_argument);
}

TEST(Dwt, ParseModeKnowsPyWaveletsNamesAndListsThemOnError) {
  for (Mode mode : kModes) EXPECT_EQ(parse_mode(mode_name(mode)), mode);
  try {
    (void)parse_mode("sym");
    FAIL() << "'sym' accepted";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("'sym'"), std::string::npos) << message;
    EXPECT_NE(message.find("antireflect"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace leakmon::dsp
