// A fresh seed for every run, printed so that a failure reproduces; LEAKMON_TEST_SEED forces one.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace leakmon::test {

inline std::uint64_t model_test_seed(const char* test_name) {
  std::uint64_t seed = 0;
  if (const char* forced = std::getenv("LEAKMON_TEST_SEED")) {
    seed = std::strtoull(forced, nullptr, 10);
  } else {
    seed = (static_cast<std::uint64_t>(std::random_device{}()) << 32) ^ std::random_device{}();
  }
  std::printf("%s: seed %llu (LEAKMON_TEST_SEED=%llu reproduces)\n", test_name,
              static_cast<unsigned long long>(seed), static_cast<unsigned long long>(seed));
  return seed;
}

// A fixed seed (a case known to be representative), unless LEAKMON_TEST_SEED forces another: for
// tests whose assertion a rare fresh draw fails for a reason the docs already give, so that CI
// does not flake on it.
inline std::uint64_t model_test_seed(const char* test_name, std::uint64_t fixed) {
  std::uint64_t seed = fixed;
  if (const char* forced = std::getenv("LEAKMON_TEST_SEED")) {
    seed = std::strtoull(forced, nullptr, 10);
  }
  std::printf("%s: seed %llu (LEAKMON_TEST_SEED=%llu reproduces)\n", test_name,
              static_cast<unsigned long long>(seed), static_cast<unsigned long long>(seed));
  return seed;
}

}  // namespace leakmon::test
