// The real-data analysis as a library: the vtnsi layout table names folders that exist in the
// shared data set, with their stroke files; stroke measurement and the pair comparison on a
// small synthetic data set laid out by a table of our own; malformed files name file:line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "study/realdata.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::study {
namespace {

TEST(RealdataLayout, NamesTheLeakAndGearPairsOfTheSharedDataSet) {
  const auto layout = vtnsi_layout();
  ASSERT_EQ(layout.size(), 2u);
  EXPECT_EQ(layout[0].faulty.folder, "Act_4_seal_defect");
  EXPECT_EQ(layout[0].healthy.folder, "Act_1");
  EXPECT_EQ(layout[1].faulty.folder, "Act_3_gear_damage");
  EXPECT_EQ(layout[1].healthy.folder, "Act_2");
  const std::filesystem::path data =
      std::filesystem::path(test::shared_data_dir()) / "vtnsi_actuator";
  for (const auto& pair : layout) {
    for (const UnitSpec* unit : {&pair.faulty, &pair.healthy}) {
      ASSERT_TRUE(std::filesystem::is_directory(data / unit->folder)) << (data / unit->folder);
      EXPECT_GE(stroke_files(data / unit->folder).size(), 95u) << unit->folder;
    }
  }
}

// A stroke: still for 500 samples, turning for 600, then held; port 1 pressurised, with noise
// of `sigma` counts on it.
void write_stroke(const std::filesystem::path& path, double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sigma);
  std::ofstream f(path);
  f << "Time\tAngle\tPG_1\tPG_2\n";
  for (int i = 0; i < 2000; ++i) {
    const double angle = i < 500 ? 0.0 : (i < 1100 ? (i - 500) * 0.15 : 90.0);
    f << i * 0.001 << '\t' << angle << '\t' << 3000.0 + noise(rng) << '\t' << 1000.0 << "\r\n";
  }
}

TEST(RealdataAnalysis, SeparatesANoisierUnitFromItsPairByATableOfFolders) {
  const std::filesystem::path data = test::scratch_dir("study_realdata_synthetic");
  std::mt19937_64 rng(42);
  for (const auto& [folder, sigma] : {std::pair{"noisy", 20.0}, std::pair{"quiet", 5.0}}) {
    std::filesystem::create_directories(data / folder);
    for (int s = 0; s < 6; ++s) {
      write_stroke(data / folder / ("stroke_" + std::to_string(s) + ".txt"), sigma, rng);
    }
    std::ofstream(data / folder / "notes.md") << "not a stroke\n";
  }
  const std::vector<PairSpec> layout = {{"noisy vs quiet", {"noisy", "x"}, {"quiet", "y"}}};
  const RealdataResult result = analyse_realdata(data, layout, 0.05);
  ASSERT_EQ(result.pairs.size(), 1u);
  const PairResult& pair = result.pairs[0];
  ASSERT_EQ(pair.faulty.strokes.size(), 6u);  // the .md file is not a stroke
  ASSERT_EQ(pair.healthy.strokes.size(), 6u);
  const Stroke& s = pair.faulty.strokes[0];
  EXPECT_EQ(s.file, "stroke_0.txt");
  EXPECT_NEAR(s.stroke_samples, 600.0, 20.0);
  EXPECT_NEAR(s.hold_load, 2000.0, 5.0);
  ASSERT_EQ(pair.features.size(), 4u);
  EXPECT_EQ(pair.features[0].name, "stroke_index");
  EXPECT_EQ(pair.features[0].auc_greater, 1.0);  // every noisy stroke above every quiet one
  EXPECT_EQ(pair.features[1].name, "hold_index");
  EXPECT_EQ(pair.features[1].auc_greater, 1.0);
  // The index ratio follows the noise ratio (4) within the estimate's scatter.
  EXPECT_NEAR(pair.features[0].median_faulty / pair.features[0].median_healthy, 4.0, 1.0);
  // The paper's rule flags strokes below the healthy baseline: none of the noisy unit's.
  EXPECT_EQ(pair.flagged_faulty, 0.0);
  EXPECT_LE(pair.flagged_healthy, 1.0 / 6.0);
  EXPECT_NE(realdata_markdown(result).find("| noisy vs quiet | stroke_index |"), std::string::npos);
}

TEST(RealdataAnalysis, MalformedStrokeAndEmptyFolderFailWithTheirLocation) {
  const std::filesystem::path data = test::scratch_dir("study_realdata_bad");
  std::filesystem::create_directories(data / "a");
  std::filesystem::create_directories(data / "b");
  std::ofstream(data / "a" / "s.txt") << "Angle\tPG_1\tPG_2\n1\t2\t3\n1\t2\n";
  try {
    measure_stroke((data / "a" / "s.txt").string());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("s.txt:3: column 3 ('PG_2') missing"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(stroke_files(data / "b"), std::runtime_error);
}

}  // namespace
}  // namespace leakmon::study
