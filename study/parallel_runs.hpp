// The worker pool both evaluations run their cases on: `jobs` threads take the next case in
// turn, so each result lands at its case's index and the output does not depend on the
// threads' order (byte-identical files for any --jobs).
#pragma once

#include <fmt/format.h>

#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace leakmon::study {

// Called after each finished run, one call at a time.
using Progress = std::function<void(std::size_t done, std::size_t total)>;

// Evaluates every run with `evaluate(run)` on `jobs` threads. The first run that throws stops
// the pool (no further case is started) and is rethrown as "run ID: what" once all threads end.
template <class Result, class Run, class Evaluate>
std::vector<Result> run_in_parallel(const std::vector<Run>& runs, int jobs,
                                    const Progress& progress, Evaluate evaluate) {
  std::vector<Result> results(runs.size());
  std::atomic<std::size_t> next{0};
  std::size_t done = 0;
  std::mutex lock;
  std::string failure;
  auto worker = [&] {
    for (std::size_t i = next++; i < runs.size(); i = next++) {
      try {
        results[i] = evaluate(runs[i]);
      } catch (const std::exception& e) {
        std::lock_guard guard(lock);
        failure = fmt::format("run {}: {}", runs[i].id, e.what());
        next = runs.size();
        return;
      }
      std::lock_guard guard(lock);
      ++done;
      if (progress) progress(done, runs.size());
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (!failure.empty()) throw std::runtime_error(failure);
  return results;
}

}  // namespace leakmon::study
