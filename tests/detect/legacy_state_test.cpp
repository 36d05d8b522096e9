// States written by the build before issue 26 (tests/detect/data/legacy_states/, see
// legacy_state_cases.hpp) load in this build's detectors, which then decide exactly as that
// build did after loading them: every decision of the following seconds, to the bit.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "detect/legacy_state.hpp"
#include "tests/detect/legacy_state_cases.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::detect {
namespace {

std::string read(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in) << path;
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string fixture(const std::string& name) {
  return test::source_dir() + "/tests/detect/data/legacy_states/" + name;
}

class LegacyState : public ::testing::TestWithParam<test::LegacyCase> {};

TEST_P(LegacyState, LoadsAndDecidesAsTheBuildThatWroteIt) {
  const test::LegacyCase& c = GetParam();
  const DetectorState old = DetectorState::parse(read(fixture(c.name + ".state")));
  auto detector = test::make_legacy_detector(c);
  // A layout from before (fused's own is unchanged; its members' are not).
  const DetectorState fresh = detector->export_state();
  const bool composite = c.kind == "fused";
  ASSERT_LT(composite ? old.get_nested("m0").version() : old.version(),
            composite ? fresh.get_nested("m0").version() : fresh.version());
  detector->import_state(old);
  // The same observations from the cut on.
  test::LegacyStream stream(c);
  Observation o = stream.next();
  while (o.t < c.cut) o = stream.next();
  std::vector<std::string> lines;
  bool judged = false;
  for (; o.t < c.end; o = stream.next()) {
    const Decision d = detector->update(o);
    judged |= !std::isnan(d.score);
    lines.push_back(test::decision_line(o, d));
  }
  EXPECT_TRUE(judged) << c.name;

  std::istringstream expected(read(fixture(c.name + ".decisions")));
  std::string word, hash;
  std::size_t hops = 0;
  expected >> word >> hash >> word >> hops;
  ASSERT_EQ(lines.size(), hops);
  // Where they part, when they do: the sampled lines first.
  std::string line;
  std::getline(expected, line);
  while (std::getline(expected, line)) {
    const std::size_t space = line.find(' ');
    const std::size_t i = std::stoul(line.substr(0, space));
    ASSERT_LT(i, lines.size());
    ASSERT_EQ(lines[i], line.substr(space + 1)) << c.name << ", decision " << i;
  }
  EXPECT_EQ(test::lines_hash(lines), hash) << c.name;
  // And it says it has learned, as `leakmon state show` reads it.
  EXPECT_TRUE(has_learned(old)) << c.name;
  EXPECT_TRUE(has_learned(detector->export_state())) << c.name;
}

INSTANTIATE_TEST_SUITE_P(EveryLayout, LegacyState, ::testing::ValuesIn(test::legacy_cases()),
                         [](const auto& param_info) { return param_info.param.name; });

// The fields that were saved but never computed (index_cusum 3's learned_log_supply and
// block_temps) are gone, and no value is left as a position in a list.
TEST(LegacyState, ConvertedStatesHaveNamedValuesOnly) {
  for (const auto& c : test::legacy_cases()) {
    const DetectorState old = DetectorState::parse(read(fixture(c.name + ".state")));
    auto detector = test::make_legacy_detector(c);
    detector->import_state(old);
    const DetectorState now = detector->export_state();
    for (const auto& [key, values] : now.entries()) {
      EXPECT_EQ(key.find("learned_log_supply"), std::string::npos) << c.name;
      EXPECT_EQ(key.find("block_temps"), std::string::npos) << c.name;
      EXPECT_EQ(key.find("chamber_supply "), std::string::npos) << c.name;
    }
    EXPECT_FALSE(now.has("supply")) << c.name << ": the supply's values by position";
    EXPECT_FALSE(now.has("last_decision")) << c.name;
    EXPECT_FALSE(now.has("test.chamber_supply")) << c.name;
  }
}

TEST(LegacyState, ALayoutNeitherOldNorCurrentIsRefused) {
  for (const auto& c : test::legacy_cases()) {
    DetectorState old = DetectorState::parse(read(fixture(c.name + ".state")));
    auto detector = test::make_legacy_detector(c);
    DetectorState older(old.kind(), old.version() - 1);
    for (const auto& [key, values] : old.entries()) older.put(key, values);
    EXPECT_THROW(detector->import_state(older), StateError) << c.name;
  }
}

// The old layout's checks still hold: a truncated list or an out-of-range position is refused.
TEST(LegacyState, DamagedOldStatesAreRefused) {
  const auto cases = test::legacy_cases();
  for (const auto& c : cases) {
    if (c.kind != "index_cusum") continue;
    const DetectorState old = DetectorState::parse(read(fixture(c.name + ".state")));
    auto detector = test::make_legacy_detector(c);
    DetectorState chamber = old;
    auto values = chamber.get_list("chamber_supply");
    values.pop_back();
    chamber.put("chamber_supply", values);
    EXPECT_THROW(detector->import_state(chamber), StateError) << c.name;
    DetectorState temps = old;
    temps.put_count("block_temps", old.get_count("block_hop") + 1);
    EXPECT_THROW(detector->import_state(temps), StateError) << c.name;
    DetectorState trend = old;
    trend.put_count("trend_next", old.get_list("trend").size());
    EXPECT_THROW(detector->import_state(trend), StateError) << c.name;
    // After a refused import the detector starts learning afresh.
    EXPECT_TRUE(detector->update(test::LegacyStream(c).next()).learning);
  }
}

}  // namespace
}  // namespace leakmon::detect
