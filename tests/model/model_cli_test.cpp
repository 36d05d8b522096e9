// `leakmon model check` as a user runs it: JSON of FORMATS.md, the report with plots, and
// clear errors for unusable captures.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "capture/capture.hpp"
#include "model/synthetic_case.hpp"
#include "tests/model/test_seed.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::model {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int run(const std::string& args, const std::string& log) {
  const std::string command = test::leakmon_binary() + " " + args + " > " + log + " 2>&1";
  return std::system(command.c_str());
}

TEST(ModelCli, ChecksACaptureAndWritesJsonAndReport) {
  const auto seed = test::model_test_seed("ModelCli.ChecksACaptureAndWritesJsonAndReport");
  const std::string dir = test::scratch_dir("model_cli_check");
  const SyntheticCase c = draw_case(seed, "internal_leakage", {40.0});
  capture::write_capture(dir + "/capture.csv", simulate_case(c));
  ASSERT_EQ(run("model check --data " + dir + "/capture.csv --json " + dir +
                    "/result.json --report " + dir + "/report",
                dir + "/log.txt"),
            0)
      << read_file(dir + "/log.txt");
  // The JSON is read back by Python's parser, the way other tools consume it.
  char true_value[32];
  std::snprintf(true_value, sizeof true_value, "%.9g", c.main_value);
  const std::string check = test::python() +
                            " -c \"import json,sys; r=json.load(open(sys.argv[1])); "
                            "assert r['cause']=='internal_leakage', r['cause']; "
                            "assert 'onset_s' not in r['causes'][0]; "
                            "assert r['rig']['changed']==[]; "
                            "assert abs(r['params']['C_L']/" +
                            true_value +
                            "-1)<0.25; "
                            "assert set(r['calibrated'])=={'beta','Kv','m','b'}; "
                            "assert len(r['ranking'])==11; "
                            "assert r['nrmse_after']<r['nrmse_before']\" " +
                            dir + "/result.json";
  EXPECT_EQ(std::system(check.c_str()), 0) << read_file(dir + "/result.json");
  const std::string report = read_file(dir + "/report/report.md");
  EXPECT_NE(report.find("internal_leakage"), std::string::npos);
  for (const char* png :
       {"residuals_time.png", "residuals_regressors.png", "residuals_spectrum.png"}) {
    EXPECT_GT(std::filesystem::file_size(dir + "/report/" + png), 10000u) << png;
  }
}

TEST(ModelCli, RefusesACaptureWithoutPressures) {
  const std::string dir = test::scratch_dir("model_cli_columns");
  {
    std::ofstream out(dir + "/capture.csv");
    out << "t,u,x\n0,0,0\n0.002,0,0\n";
  }
  EXPECT_NE(
      run("model check --data " + dir + "/capture.csv --json " + dir + "/r.json", dir + "/log.txt"),
      0);
  const std::string log = read_file(dir + "/log.txt");
  EXPECT_NE(log.find(dir + "/capture.csv"), std::string::npos) << log;
  EXPECT_NE(log.find("'p1', 'p2'"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir + "/r.json"));
}

// `model evaluate --first-case K` draws case K of the sequence (its seed, class and effect) as
// the whole run does: to re-run one miss of a long evaluation, or resume it. Short captures of
// the paper's rig; the per-case lines are deterministic.
TEST(ModelCli, EvaluateFromACaseDrawsThatCaseOfTheSequence) {
  const std::string dir = test::scratch_dir("model_cli_first_case");
  const std::string common = "model evaluate --duration 24 --classes library,clean --seed 4100 ";
  ASSERT_EQ(run(common + "--cases 3 --out " + dir + "/all", dir + "/all.log"), 0)
      << read_file(dir + "/all.log");
  ASSERT_EQ(run(common + "--cases 3 --first-case 2 --out " + dir + "/one", dir + "/one.log"), 0)
      << read_file(dir + "/one.log");
  const auto case_lines = [](const std::string& log) {
    std::istringstream in(log);
    std::string line, out;
    while (std::getline(in, line)) {
      if (line.rfind("case ", 0) == 0) {
        // The wall time differs from run to run.
        const auto seconds = line.find(" s; leading");
        out += line.substr(0, line.rfind(' ', seconds - 1)) + line.substr(seconds) + "\n";
      }
    }
    return out;
  };
  const std::string all = case_lines(read_file(dir + "/all.log"));
  const std::string one = case_lines(read_file(dir + "/one.log"));
  ASSERT_NE(one.find("case 2 seed 4102: "), std::string::npos) << one;
  EXPECT_EQ(one.find("case 0 "), std::string::npos) << one;
  EXPECT_NE(all.find(one), std::string::npos) << "whole run:\n" << all << "from case 2:\n" << one;
  EXPECT_NE(run(common + "--cases 3 --first-case 3 --out " + dir + "/bad", dir + "/bad.log"), 0);
  EXPECT_NE(read_file(dir + "/bad.log").find("--first-case"), std::string::npos)
      << read_file(dir + "/bad.log");
}

}  // namespace
}  // namespace leakmon::model
