// Every subcommand of build/bin/leakmon answers --help with its usage and exit code 0, and the
// top-level help lists them all.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

struct Outcome {
  int exit_code;
  std::string output;
};

Outcome run_leakmon(const std::string& args) {
  // One folder per test case: ctest runs the cases as parallel processes, and scratch_dir()
  // empties the folder it names.
  const std::string log =
      test::scratch_dir(std::string("cli_help_") +
                        ::testing::UnitTest::GetInstance()->current_test_info()->name()) +
      "/leakmon.log";
  const int status =
      std::system((test::leakmon_binary() + " " + args + " > " + log + " 2>&1").c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

constexpr const char* kSubcommands[] = {"run",      "replay",   "check-config", "probe",
                                        "status",   "ack",      "features",     "sim",
                                        "evaluate", "realdata", "model"};

TEST(CliHelp, EverySubcommandPrintsItsUsage) {
  for (const char* name : kSubcommands) {
    const Outcome help = run_leakmon(std::string(name) + " --help");
    EXPECT_EQ(help.exit_code, 0) << name << "\n" << help.output;
    EXPECT_NE(help.output.find(std::string("usage: leakmon ") + name), std::string::npos)
        << name << "\n"
        << help.output;
  }
}

TEST(CliHelp, TopLevelHelpListsEverySubcommand) {
  const Outcome help = run_leakmon("--help");
  EXPECT_EQ(help.exit_code, 0);
  for (const char* name : kSubcommands) {
    EXPECT_NE(help.output.find(std::string("  ") + name + " "), std::string::npos) << name;
  }
  EXPECT_EQ(run_leakmon("no-such-command").exit_code, 2);
}

}  // namespace
}  // namespace leakmon
