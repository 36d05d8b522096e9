// BlockFeatures (one channel, many samples per call, kLanes windows at a time) against the
// batch transform and PyWavelets: every window of random signals with gaps, every mode, several
// wavelets, levels and steps, cut into blocks of many sizes (most not a multiple of the step);
// low-noise signals on the rig's pressure level; the one-by-one fallback; no allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "dsp/block_features.hpp"
#include "dsp/streaming_features.hpp"
#include "tests/dsp/pywt_oracle.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::dsp {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr Mode kModes[] = {Mode::zero,          Mode::constant,      Mode::symmetric,
                           Mode::reflect,       Mode::periodic,      Mode::smooth,
                           Mode::periodization, Mode::antisymmetric, Mode::antireflect};

// A random walk plus noise around the rig's pressure level; `gaps`: a lone NaN and a run of 7.
std::vector<double> pressure(std::size_t n, std::uint64_t seed, double noise, bool gaps) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> x(n);
  double level = 8.65e6;
  for (auto& v : x) {
    level += 0.4 * noise * normal(rng);
    v = level + noise * normal(rng);
  }
  if (gaps) {
    x[(137 + seed) % n] = kNaN;
    for (std::size_t i = 0; i < 7; ++i) x[(n / 2 + seed + i) % n] = kNaN;
  }
  return x;
}

void expect_same(const DetailFeature& block, const DetailFeature& batch, const std::string& label) {
  ASSERT_EQ(block.valid, batch.valid) << label;
  if (!batch.valid) {
    EXPECT_TRUE(std::isnan(block.rms) && std::isnan(block.energy)) << label;
    return;
  }
  EXPECT_LE(std::abs(block.rms - batch.rms), 1e-12 * std::abs(batch.rms)) << label;
  EXPECT_LE(std::abs(block.energy - batch.energy), 1e-12 * std::abs(batch.energy)) << label;
}

// Feeds `x` in blocks of `block` samples (the last one shorter) and checks every window
// against sliding_detail_features: same count, order, last sample, validity and values.
void check_blocks_equal_batch(const FeatureParams& params, const std::vector<double>& x,
                              std::size_t block, bool expect_incremental) {
  const auto batch = sliding_detail_features(x, params);
  BlockFeatures features(params);
  EXPECT_EQ(features.incremental(), expect_incremental);
  const std::string label = params.wavelet + " " + std::string(mode_name(params.mode)) + " level " +
                            std::to_string(params.level) + " window " +
                            std::to_string(params.window) + " step " + std::to_string(params.step) +
                            " block " + std::to_string(block);
  std::size_t w = 0;
  for (std::size_t from = 0; from < x.size(); from += block) {
    const std::size_t count = std::min(block, x.size() - from);
    features.push_block(std::span<const double>(x).subspan(from, count),
                        [&](const WindowFeature& f) {
                          ASSERT_LT(w, batch.size()) << label;
                          EXPECT_EQ(f.last_sample, w * params.step + params.window - 1) << label;
                          // Windows complete as soon as their last sample arrives.
                          EXPECT_LT(f.last_sample, from + count) << label;
                          expect_same(f.feature, batch[w], label + " window " + std::to_string(w));
                          ++w;
                        });
    // ... and not later: every window ending within this block has been delivered.
    const std::size_t seen = from + count;
    const std::size_t due = seen < params.window ? 0 : (seen - params.window) / params.step + 1;
    EXPECT_EQ(w, std::min(due, batch.size())) << label << " after " << seen << " samples";
  }
  EXPECT_EQ(w, batch.size()) << label;
  EXPECT_EQ(features.samples_seen(), x.size()) << label;
}

TEST(BlockFeatures, PaperDefaultsEqualBatchForEveryBlockSize) {
  const FeatureParams params;  // db8, level 2, window 400, step 20, symmetric
  const auto x = pressure(4003, 1, 5e3, true);
  for (std::size_t block : {4003u, 1000u, 401u, 160u, 33u, 20u, 7u, 1u}) {
    check_blocks_equal_batch(params, x, block, true);
  }
}

TEST(BlockFeatures, EveryModeSeveralWaveletsLevelsAndStepsEqualBatch) {
  struct Setup {
    const char* wavelet;
    int level;
    std::size_t window, step;
    bool incremental;
  };
  const Setup setups[] = {
      {"db8", 2, 400, 20, true},  {"db8", 2, 400, 10, false},  // 10: phase changes: fallback
      {"db8", 2, 400, 7, false},  {"haar", 1, 64, 2, true},    {"db4", 3, 256, 8, true},
      {"sym5", 2, 200, 12, true}, {"coif2", 2, 300, 40, true}, {"db8", 4, 400, 32, true},
      {"db2", 1, 32, 500, true},  // step longer than the window: samples in no window
      {"db20", 2, 400, 20, true},
  };
  std::uint64_t seed = 10;
  for (const Setup& s : setups) {
    for (Mode mode : kModes) {
      const FeatureParams params{s.wavelet, s.level, s.window, s.step, mode};
      // Enough windows for two full batches of lanes and a partial one.
      const std::size_t n = s.window + (2 * BlockFeatures::kLanes + 3) * s.step + 5;
      const auto x = pressure(n, ++seed, 5e3, true);
      check_blocks_equal_batch(params, x, n, s.incremental);
      check_blocks_equal_batch(params, x, 3 * s.step + 1, s.incremental);
    }
  }
}

// MODEL.md's noise-free plant gives a d2 RMS of ~0.1 kPa on ~8.65 MPa: the batch transform's
// own rounding of the level is then a sizeable part of the energy, so the block path agrees to
// 1e-12 only if every lane sums every coefficient in the batch order (a precomputed boundary
// map, which sums in another order, was off by 3e-12 to 2e-11 here).
TEST(BlockFeatures, LowNoiseOnTheRigPressureLevelStillEqualsBatch) {
  for (const double noise : {100.0, 1.0}) {
    const auto x = pressure(2400, static_cast<std::uint64_t>(noise) + 40, noise, false);
    for (std::size_t block : {2400u, 173u}) {
      check_blocks_equal_batch(FeatureParams{}, x, block, true);
      check_blocks_equal_batch({"db8", 4, 400, 32, Mode::smooth}, x, block, true);
      check_blocks_equal_batch({"db8", 2, 400, 20, Mode::periodization}, x, block, true);
      check_blocks_equal_batch({"db8", 3, 400, 24, Mode::antireflect}, x, block, true);
    }
  }
}

TEST(BlockFeatures, MatchesPyWavelets) {
  test::PywtOracle oracle("block_features");
  struct Case {
    FeatureParams params;
    std::vector<double> x;
    std::size_t request = 0;
  };
  // Cases are filled in place: GCC 12 at -O3 reports a false -Wmaybe-uninitialized for the
  // wavelet string of a brace-initialised Case moved into the vector.
  std::vector<Case> cases(std::size(kModes) + 1);
  std::uint64_t seed = 200;
  for (std::size_t i = 0; i < std::size(kModes); ++i) {
    Case& c = cases[i];
    c.params.mode = kModes[i];
    c.x = pressure(1300, ++seed, 5e3, true);
    c.request = oracle.sliding(c.x, "db8", std::string(mode_name(kModes[i])), 2, 400, 20);
  }
  Case& quiet = cases.back();
  quiet.params.mode = Mode::symmetric;
  quiet.x = pressure(1300, 7, 100.0, false);
  quiet.request = oracle.sliding(quiet.x, "db8", "symmetric", 2, 400, 20);
  oracle.run();
  for (const Case& c : cases) {
    const std::string label = std::string(mode_name(c.params.mode));
    const auto& expected_rms = oracle.results(c.request).at(0);
    const auto& expected_energy = oracle.results(c.request).at(1);
    BlockFeatures features(c.params);
    std::size_t w = 0;
    features.push_block(c.x, [&](const WindowFeature& f) {
      ASSERT_LT(w, expected_rms.size()) << label;
      if (std::isnan(expected_rms[w])) {
        EXPECT_FALSE(f.feature.valid) << label << " window " << w;
      } else {
        ASSERT_TRUE(f.feature.valid) << label << " window " << w;
        EXPECT_LE(std::abs(f.feature.rms - expected_rms[w]), 1e-12 * expected_rms[w])
            << label << " " << w;
        EXPECT_LE(std::abs(f.feature.energy - expected_energy[w]), 1e-12 * expected_energy[w])
            << label << " " << w;
      }
      ++w;
    });
    EXPECT_EQ(w, expected_rms.size()) << label;
  }
}

TEST(BlockFeatures, GapsInvalidateExactlyTheWindowsThatHoldThem) {
  FeatureParams params;
  auto x = pressure(2000, 3, 5e3, false);
  x[1150] = kNaN;
  BlockFeatures features(params);
  std::size_t windows = 0;
  std::size_t invalid = 0;
  features.push_block(x, [&](const WindowFeature& f) {
    const std::uint64_t start = f.last_sample + 1 - params.window;
    const bool holds_gap = start <= 1150 && 1150 <= f.last_sample;
    EXPECT_EQ(f.feature.valid, !holds_gap) << "window at " << start;
    if (!holds_gap) {
      EXPECT_GT(f.feature.rms, 1e3);
    }
    invalid += holds_gap ? 1 : 0;
    ++windows;
  });
  EXPECT_EQ(windows, 81u);
  EXPECT_EQ(invalid, 20u);  // the windows starting at 760, 780, ..., 1140
}

TEST(BlockFeatures, ResetStartsAfreshAndEqualsBatchOfTheRest) {
  const FeatureParams params;
  const auto x = pressure(1500, 5, 5e3, false);
  BlockFeatures features(params);
  std::size_t before = 0;
  features.push_block(std::span<const double>(x).first(555),
                      [&](const WindowFeature&) { ++before; });
  EXPECT_EQ(before, 8u);
  features.reset();
  EXPECT_EQ(features.samples_seen(), 0u);
  const auto rest = std::span<const double>(x).subspan(300);
  const auto batch = sliding_detail_features(rest, params);
  std::size_t w = 0;
  features.push_block(rest, [&](const WindowFeature& f) {
    ASSERT_LT(w, batch.size());
    expect_same(f.feature, batch[w], "after reset, window " + std::to_string(w));
    ++w;
  });
  EXPECT_EQ(w, batch.size());
}

TEST(BlockFeatures, PushBlockAllocatesNothingAfterConstruction) {
  for (std::size_t step : {20u, 10u}) {  // incremental and one-by-one fallback
    FeatureParams params;
    params.step = step;
    BlockFeatures features(params);
    const auto x = pressure(3000, 4, 5e3, true);
    std::size_t windows = 0;
    test::AllocationScope scope;
    for (std::size_t block : {3000u, 37u}) {
      for (std::size_t from = 0; from < x.size(); from += block) {
        const std::size_t count = std::min(block, x.size() - from);
        features.push_block(std::span<const double>(x).subspan(from, count),
                            [&](const WindowFeature&) { ++windows; });
      }
      features.reset();
    }
    EXPECT_EQ(scope.count(), 0u) << "step " << step;
    EXPECT_EQ(windows, 2 * ((3000 - 400) / step + 1)) << "step " << step;
  }
}

TEST(BlockFeatures, InvalidParametersAreRejected) {
  FeatureParams p;
  p.step = 0;
  EXPECT_THROW(BlockFeatures{p}, std::invalid_argument);
  p = {};
  p.wavelet = "db42";
  EXPECT_THROW(BlockFeatures{p}, std::invalid_argument);
}

}  // namespace
}  // namespace leakmon::dsp
