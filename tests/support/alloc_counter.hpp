// Counts heap allocations made by the calling thread, to prove that real-time code paths
// allocate nothing. Linking leakmon_test_support replaces the global operator new/delete.
#pragma once

#include <cstdint>

namespace leakmon::test {

// Allocations (operator new, any form) made by this thread since it started.
std::uint64_t thread_allocations();

// Counts allocations made by the current thread within its lifetime.
class AllocationScope {
 public:
  AllocationScope() : start_(thread_allocations()) {}
  std::uint64_t count() const { return thread_allocations() - start_; }

 private:
  std::uint64_t start_;
};

}  // namespace leakmon::test
