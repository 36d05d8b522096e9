// The CAN drivers as the daemon sees them: `leakmon check-config` builds them through the
// driver registry from a whole daemon configuration, and a mistake in a signal is reported at
// its file:line:column.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Result {
  int status = -1;
  std::string output;
};

Result run(const std::string& command) {
  Result r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 512> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe) != nullptr) r.output += buffer.data();
  const int status = pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

TEST(CanDaemonConfig, CheckConfigBuildsTheCanlogDriverThroughTheRegistry) {
  const Result ok = run(test::leakmon_binary() + " check-config " + test::source_dir() +
                        "/io/canlog/replay_daemon.yaml");
  EXPECT_EQ(ok.status, 0) << ok.output;
}

TEST(CanDaemonConfig, SignalMistakesNameTheirLocation) {
  const std::string dir = test::scratch_dir("can_daemon_config");
  std::ifstream in(test::source_dir() + "/io/canlog/replay_daemon.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string from = "id: 0x102, start_bit: 7";
  const auto at = yaml.find(from);
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, from.size(), "id: 0x902, start_bit: 7");  // 0x902 needs 12 bits
  std::ofstream(dir + "/daemon.yaml") << yaml;
  std::filesystem::copy_file(test::source_dir() + "/io/canlog/sample.log", dir + "/sample.log");
  const Result bad = run(test::leakmon_binary() + " check-config " + dir + "/daemon.yaml");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find(dir + "/daemon.yaml:13:26"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("11 bits"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace leakmon
