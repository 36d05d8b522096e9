// The binary matches its documentation: every command in README's command table exists (`--help`
// exits 0), every example configuration in the repository passes `leakmon check-config`, and a
// capture with a header but no rows is the same "no samples" error (exit 1) for every command
// that reads captures.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Outcome {
  int exit_code;
  std::string output;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

Outcome run_leakmon(const std::string& args, const std::string& scratch = "cli_edges") {
  // One folder per test case: ctest runs the cases as parallel processes, and scratch_dir()
  // empties the folder it names.
  const std::string log =
      test::scratch_dir(scratch + "_log_" +
                        ::testing::UnitTest::GetInstance()->current_test_info()->name()) +
      "/leakmon.log";
  const int status =
      std::system((test::leakmon_binary() + " " + args + " > " + log + " 2>&1").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_file(log)};
}

// `leakmon WORDS...` spans of README's command table, e.g. "state show|reset --config C.yaml"
// -> "state show", "state reset": the subcommand words before the first option or argument.
std::set<std::string> readme_commands() {
  std::set<std::string> commands;
  std::istringstream in(read_file(test::source_dir() + "/README.md"));
  for (std::string line; std::getline(in, line);) {
    if (!line.starts_with("| `leakmon ")) continue;
    for (auto pos = line.find("`leakmon "); pos != std::string::npos;
         pos = line.find("`leakmon ", pos + 1)) {
      const auto end = line.find('`', pos + 1);
      std::istringstream words(line.substr(pos + 9, end - pos - 9));
      std::vector<std::string> prefixes{""};
      for (std::string word; words >> word;) {
        if (word.empty() || word.front() == '-' ||
            !std::islower(static_cast<unsigned char>(word.front()))) {
          break;
        }
        std::vector<std::string> next;
        std::size_t start = 0;
        // Alternatives are written `show\|reset` inside the table.
        while (true) {
          auto bar = word.find("\\|", start);
          const std::string alternative = word.substr(start, bar - start);
          for (const auto& prefix : prefixes) {
            next.push_back(prefix.empty() ? alternative : prefix + " " + alternative);
          }
          if (bar == std::string::npos) break;
          start = bar + 2;
        }
        prefixes = next;
      }
      for (const auto& command : prefixes) {
        if (!command.empty()) commands.insert(command);
      }
    }
  }
  return commands;
}

TEST(CliEdges, EveryReadmeCommandExists) {
  const auto commands = readme_commands();
  // The parse itself is checked: the table names these at least.
  for (const char* known : {"run", "check-config", "status", "ack", "replay", "state show",
                            "state reset", "model check", "features"}) {
    EXPECT_TRUE(commands.count(known)) << known;
  }
  for (const auto& command : commands) {
    const Outcome help = run_leakmon(command + " --help");
    EXPECT_EQ(help.exit_code, 0) << command << "\n" << help.output;
  }
}

// Every YAML file in the repository that is a daemon configuration (it has a top-level
// `drivers:`); simulator scenarios and driver snippets are not. Devices and the port are not
// probed: the examples name a CAN bus and a port this machine need not have.
TEST(CliEdges, EveryExampleConfigurationPassesCheckConfig) {
  namespace fs = std::filesystem;
  std::vector<std::string> configs;
  for (const auto& entry : fs::recursive_directory_iterator(test::source_dir())) {
    const std::string path = entry.path().string();
    if (entry.path().extension() != ".yaml") continue;
    // Fuzzing seeds are deliberately broken; build trees hold copies.
    if (path.find("/build") != std::string::npos || path.find("/.git/") != std::string::npos ||
        path.find("/fuzz/") != std::string::npos) {
      continue;
    }
    const std::string text = read_file(path);
    if (text.starts_with("drivers:") || text.find("\ndrivers:") != std::string::npos) {
      configs.push_back(path);
    }
  }
  EXPECT_GE(configs.size(), 5u) << "demo, sim, replay, canlog replay, bench";
  // Examples without `state:` keep their state in $STATE_DIRECTORY, which must be writable.
  ::setenv("STATE_DIRECTORY", test::scratch_dir("cli_edges_state").c_str(), 1);
  for (const auto& config : configs) {
    const Outcome check = run_leakmon("check-config --no-probe " + config);
    EXPECT_EQ(check.exit_code, 0) << check.output;
    EXPECT_NE(check.output.find(": ok ("), std::string::npos) << check.output;
  }
}

TEST(CliEdges, HeaderOnlyCaptureIsNoSamplesForEveryCommand) {
  const std::string dir = test::scratch_dir("cli_edges_header_only");
  std::ofstream(dir + "/empty.csv") << "# sample_rate_hz: 500\nt,p1,p2,u,x,xref\n";
  std::ofstream(dir + "/config.yaml")
      << "drivers: [{name: rig, type: sim, scenario: healthy}]\n"
         "actuators: [{name: cyl, channels: {p1: rig.p1, p2: rig.p2, u: rig.u, x: rig.x}}]\n"
         "state: {directory: " +
             dir + "/state}\n";
  const std::string empty = dir + "/empty.csv";
  for (const std::string& command :
       {"features --in " + empty + " --channel p1 --out " + dir + "/f.csv",
        "replay --in " + empty + " --events " + dir + "/e.jsonl",
        "model check --data " + empty + " --json " + dir + "/r.json",
        "learn --config " + dir + "/config.yaml --in " + empty}) {
    const Outcome outcome = run_leakmon(command);
    EXPECT_EQ(outcome.exit_code, 1) << command << "\n" << outcome.output;
    EXPECT_NE(outcome.output.find(empty + ": no samples"), std::string::npos) << command << "\n"
                                                                              << outcome.output;
  }
}

}  // namespace
}  // namespace leakmon
