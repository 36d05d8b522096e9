// The worker pool both evaluations share (study/parallel_runs.hpp): results land at their run's
// index whatever the number of threads, progress counts every finished run once, and the first
// run that throws stops the pool and is reported by its id.
#include "study/parallel_runs.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

namespace leakmon::study {
namespace {

struct Case {
  int id = 0;
};

std::vector<Case> cases(int n) {
  std::vector<Case> runs;
  for (int i = 0; i < n; ++i) runs.push_back({100 + i});
  return runs;
}

TEST(RunInParallel, ResultsInTheOrderOfTheRunsForAnyNumberOfThreads) {
  const auto runs = cases(23);
  for (int jobs : {1, 2, 5}) {
    std::vector<std::size_t> seen;
    const auto results = run_in_parallel<std::string>(
        runs, jobs,
        [&](std::size_t done, std::size_t total) {
          EXPECT_EQ(total, runs.size());
          seen.push_back(done);
        },
        [](const Case& run) { return fmt::format("r{}", run.id); });
    ASSERT_EQ(results.size(), runs.size()) << jobs;
    for (std::size_t i = 0; i < runs.size(); ++i) {
      EXPECT_EQ(results[i], fmt::format("r{}", runs[i].id)) << jobs;
    }
    ASSERT_EQ(seen.size(), runs.size()) << jobs;
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i + 1) << jobs;
  }
}

TEST(RunInParallel, TheFirstFailureStopsThePoolAndNamesItsRun) {
  const auto runs = cases(10);
  std::atomic<int> started{0};
  try {
    run_in_parallel<int>(runs, 1, {}, [&](const Case& run) {
      ++started;
      if (run.id == 103) throw std::invalid_argument("bad seed");
      return run.id;
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "run 103: bad seed");
  }
  EXPECT_EQ(started, 4);  // one thread: nothing after the failing run was started
}

}  // namespace
}  // namespace leakmon::study
