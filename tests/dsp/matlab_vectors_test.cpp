// MATLAB R2012a's own dwt output for db8 in all nine modes (../shared/data/pywt_matlab,
// db8_matlab_dwt_vectors.txt, read at test time): against MATLAB's built-in filters within
// 5e-5 RMS (they differ from PyWavelets' in the last digits), against PyWavelets' filters
// passed to MATLAB within 1e-10 RMS.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "dsp/dwt.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::dsp {
namespace {

struct MatlabCase {
  std::string pywt_mode, matlab_mode, coeffset;
  std::size_t n = 0;
  std::vector<double> x, ca, cd;
};

std::vector<double> numbers_after(const std::string& line, const std::string& tag) {
  std::istringstream words(line);
  std::string first;
  words >> first;
  EXPECT_EQ(first, tag) << line.substr(0, 40);
  std::vector<double> values;
  double v = 0;
  while (words >> v) values.push_back(v);
  return values;
}

struct MatlabFile {
  std::vector<MatlabCase> cases;
  std::vector<double> dec_lo, dec_hi;
};

MatlabFile read_matlab_vectors() {
  const std::string path = test::shared_data_dir() + "/pywt_matlab/db8_matlab_dwt_vectors.txt";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  MatlabFile file;
  std::string line;
  while (std::getline(in, line)) {
    if (line.starts_with("# pywt db8 dec_lo:"))
      file.dec_lo = numbers_after(line.substr(11), "dec_lo:");
    if (line.starts_with("# pywt db8 dec_hi:"))
      file.dec_hi = numbers_after(line.substr(11), "dec_hi:");
    if (!line.starts_with("CASE ")) continue;
    MatlabCase c;
    std::istringstream header(line.substr(5));
    header >> c.pywt_mode >> c.matlab_mode >> c.n >> c.coeffset;
    std::string x, ca, cd;
    std::getline(in, x);
    std::getline(in, ca);
    std::getline(in, cd);
    c.x = numbers_after(x, "X");
    c.ca = numbers_after(ca, "CA");
    c.cd = numbers_after(cd, "CD");
    file.cases.push_back(std::move(c));
  }
  return file;
}

double rms_error(std::span<const double> a, std::span<const double> b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum / static_cast<double>(a.size()));
}

TEST(MatlabVectors, Db8AllModesBothFilterSets) {
  const MatlabFile file = read_matlab_vectors();
  ASSERT_EQ(file.cases.size(), 36u);
  const Wavelet& db8 = wavelet("db8");
  ASSERT_EQ(file.dec_lo.size(), 16u);
  for (std::size_t i = 0; i < 16; ++i) {
    EXPECT_EQ(db8.dec_lo[i], file.dec_lo[i]);
    EXPECT_EQ(db8.dec_hi[i], file.dec_hi[i]);
  }
  std::size_t builtin = 0;
  std::size_t pywt_filters = 0;
  for (const MatlabCase& c : file.cases) {
    const std::string label =
        c.pywt_mode + "/" + c.matlab_mode + " n=" + std::to_string(c.n) + " " + c.coeffset;
    ASSERT_EQ(c.x.size(), c.n) << label;
    const DwtResult ours = dwt(c.x, db8, parse_mode(c.pywt_mode));
    ASSERT_EQ(ours.approx.size(), c.ca.size()) << label;
    ASSERT_EQ(ours.detail.size(), c.cd.size()) << label;
    const double tolerance = c.coeffset == "matlab_builtin" ? 5e-5 : 1e-10;
    (c.coeffset == "matlab_builtin" ? builtin : pywt_filters)++;
    EXPECT_LE(rms_error(ours.approx, c.ca), tolerance) << label;
    EXPECT_LE(rms_error(ours.detail, c.cd), tolerance) << label;
  }
  EXPECT_EQ(builtin, 18u);
  EXPECT_EQ(pywt_filters, 18u);
}

}  // namespace
}  // namespace leakmon::dsp
