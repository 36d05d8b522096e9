// The installed unit as systemd reads it: `systemd-analyze verify` must accept it, and its
// hardening must keep the settings the real-time daemon depends on.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>

#include "tests/daemon/daemon_process.hpp"

namespace leakmon {
namespace {

std::string run(const std::string& command, int& status) {
  std::string output;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  std::array<char, 4096> buffer{};
  while (pipe != nullptr && std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) {
    output += buffer.data();
  }
  status = pipe != nullptr ? ::pclose(pipe) : -1;
  return output;
}

std::string unit_path() { return test::binary_dir() + "/systemd/leakmon.service"; }

TEST(UnitFile, SystemdAnalyzeVerifyAcceptsIt) {
  // verify resolves ExecStart, so point it at the built binary through a copy of the unit.
  const std::string dir = test::scratch_dir("unit_file_verify");
  std::string unit = test::DaemonProcess::read_file(unit_path());
  ASSERT_FALSE(unit.empty()) << unit_path();
  const std::string installed_binary = unit.substr(
      unit.find("ExecStart=") + 10, unit.find(" run --config") - unit.find("ExecStart=") - 10);
  for (auto pos = unit.find(installed_binary); pos != std::string::npos;
       pos = unit.find(installed_binary, pos + 1)) {
    unit.replace(pos, installed_binary.size(), test::leakmon_binary());
  }
  std::ofstream(dir + "/leakmon.service") << unit;
  int status = 0;
  const std::string output = run("systemd-analyze verify " + dir + "/leakmon.service", status);
  // verify prints nothing and exits 0 for a clean unit; anything it says is a finding.
  EXPECT_EQ(status, 0) << output;
  EXPECT_EQ(output.find("leakmon.service:"), std::string::npos) << output;
}

TEST(UnitFile, KeepsTheRealTimeAndNotifyContract) {
  const std::string unit = test::DaemonProcess::read_file(unit_path());
  for (const char* line : {"Type=notify", "WatchdogSec=", "ExecReload=/bin/kill -HUP $MAINPID",
                           "Restart=on-failure", "NoNewPrivileges=yes", "ProtectSystem=strict",
                           "CapabilityBoundingSet=CAP_SYS_NICE CAP_IPC_LOCK",
                           "LimitRTPRIO=", "LimitMEMLOCK=", "AF_CAN"}) {
    EXPECT_NE(unit.find(line), std::string::npos) << "missing " << line;
  }
  EXPECT_EQ(unit.find("notify-reload"), std::string::npos) << "systemd 252 has no notify-reload";
}

}  // namespace
}  // namespace leakmon
