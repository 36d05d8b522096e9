#include "tests/support/paths.hpp"

#include <cstdlib>
#include <filesystem>

namespace leakmon::test {

std::string source_dir() { return LEAKMON_SOURCE_DIR; }
std::string binary_dir() { return LEAKMON_BINARY_DIR; }
std::string leakmon_binary() { return binary_dir() + "/bin/leakmon"; }

std::string shared_data_dir() {
  if (const char* env = std::getenv("LEAKMON_SHARED_DATA")) return env;
  return std::filesystem::weakly_canonical(std::filesystem::path(source_dir()) / ".." / "shared" /
                                           "data")
      .string();
}

std::string python() { return "/usr/bin/python3"; }

std::string scratch_dir(const std::string& test_name) {
  auto dir = std::filesystem::path(binary_dir()) / "test-scratch" / test_name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace leakmon::test
