// The CPU wake-up latency request: what it writes, that it lasts exactly as long as the object,
// that a missing device is a warning and not an error, and its configuration.
#include "realtime/cpu_latency_request.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "daemon/config.hpp"

namespace leakmon::realtime {
namespace {

namespace fs = std::filesystem;

// How many of this process's open files are `target`.
int open_descriptors_to(const fs::path& target) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator("/proc/self/fd")) {
    std::error_code error;
    const auto link = fs::read_symlink(entry.path(), error);
    if (!error && link == target) ++count;
  }
  return count;
}

fs::path temporary_file(const std::string& name) {
  const auto path = fs::temp_directory_path() / (name + "-" + std::to_string(::getpid()));
  std::ofstream(path).close();
  return path;
}

TEST(CpuLatencyRequest, WritesTheBinaryValueAndHoldsTheFileOpenForItsLifetime) {
  const auto device = temporary_file("leakmon-cpu-dma-latency");
  {
    CpuLatencyRequest request(37, device.string());
    ASSERT_TRUE(request.held()) << request.warning();
    EXPECT_EQ(open_descriptors_to(device), 1);
    CpuLatencyRequest moved = std::move(request);
    EXPECT_TRUE(moved.held());
    EXPECT_EQ(open_descriptors_to(device), 1) << "a move must not duplicate or drop the request";
  }
  EXPECT_EQ(open_descriptors_to(device), 0) << "the request must end with the object";
  std::ifstream in(device, std::ios::binary);
  std::int32_t written = -1;
  in.read(reinterpret_cast<char*>(&written), sizeof written);
  EXPECT_EQ(in.gcount(), static_cast<std::streamsize>(sizeof written));
  EXPECT_EQ(written, 37) << "the kernel reads a binary 32-bit microsecond value";
  fs::remove(device);
}

TEST(CpuLatencyRequest, MissingDeviceIsAWarningNamingIt) {
  CpuLatencyRequest request(0, "/nonexistent/cpu_dma_latency");
  EXPECT_FALSE(request.held());
  EXPECT_NE(request.warning().find("/nonexistent/cpu_dma_latency"), std::string::npos)
      << request.warning();
  EXPECT_NE(request.warning().find("No such file"), std::string::npos) << request.warning();
}

TEST(CpuLatencyRequest, TheKernelAppliesTheRequestWhilePermitted) {
  const fs::path device = CpuLatencyRequest::kDevice;
  if (!fs::exists(device) || ::access(device.c_str(), W_OK) != 0) {
    GTEST_SKIP() << device << " missing or not writable by this user: the PM QoS request "
                 << "itself cannot be checked here (the file-level tests above still ran)";
  }
  CpuLatencyRequest request(0);
  ASSERT_TRUE(request.held()) << request.warning();
  // Reading the device gives the effective (smallest) request of all holders: ours is 0.
  std::ifstream in(device, std::ios::binary);
  std::int32_t effective = -1;
  in.read(reinterpret_cast<char*>(&effective), sizeof effective);
  ASSERT_EQ(in.gcount(), static_cast<std::streamsize>(sizeof effective));
  EXPECT_EQ(effective, 0);
}

pipeline::DaemonConfig parse(const std::string& extra) {
  return daemon::parse_config(
      config::ConfigNode::load_string("drivers: [{name: rig, type: sim, scenario: healthy}]\n"
                                      "actuators: [{name: a, channels: {p1: p1}}]\n" +
                                          extra,
                                      "rig.yaml"));
}

TEST(CpuLatencyRequest, ConfiguredUnderRealtimeWithCyclictestsDefault) {
  EXPECT_EQ(parse("").cpu_wakeup_latency_us, 0);
  EXPECT_EQ(parse("realtime: {cpu_wakeup_latency_us: -1}\n").cpu_wakeup_latency_us, -1);
  EXPECT_EQ(parse("realtime: {cpu_wakeup_latency_us: 20}\n").cpu_wakeup_latency_us, 20);
  for (const std::string bad :
       {"realtime: {cpu_wakeup_latency_us: -5}\n", "realtime: {cpu_wakeup_latency_us: low}\n",
        "realtime: {cpu_wakup_latency_us: 0}\n"}) {
    try {
      parse(bad);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const config::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("rig.yaml:3:"), std::string::npos) << what;
      EXPECT_NE(what.find("latency_us"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace leakmon::realtime
