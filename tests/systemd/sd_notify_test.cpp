// The sd_notify protocol as systemd sees it: a real AF_UNIX datagram socket passed to a
// `leakmon run` process as NOTIFY_SOCKET, with WATCHDOG_USEC set as systemd sets it.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>

#include <set>

#include "capture/capture.hpp"
#include "tests/daemon/daemon_process.hpp"

namespace leakmon {
namespace {

using namespace std::chrono_literals;

class NotifySocket {
 public:
  explicit NotifySocket(const std::string& path) : path_(path) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", path.c_str());
    ::unlink(path.c_str());
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) fd_ = -1;
  }
  ~NotifySocket() {
    if (fd_ >= 0) ::close(fd_);
    ::unlink(path_.c_str());
  }
  bool ok() const { return fd_ >= 0; }
  // Reads datagrams until one contains `field`; collects all lines seen.
  bool wait_for(const std::string& field, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buffer[4096];
      const ssize_t n = ::recv(fd_, buffer, sizeof(buffer), 0);
      if (n <= 0) continue;
      const std::string message(buffer, static_cast<std::size_t>(n));
      messages.push_back(message);
      if (message.find(field) != std::string::npos) return true;
    }
    return false;
  }
  std::vector<std::string> messages;

 private:
  std::string path_;
  int fd_ = -1;
};

TEST(SdNotify, ReadyWatchdogReloadingStopping) {
  const std::string dir = test::scratch_dir("sd_notify");
  capture::Capture capture;
  capture.columns = {"t", "p1", "p2"};
  capture.values.assign(3, {});
  for (int i = 0; i < 2000; ++i) {
    capture.values[0].push_back(i * 0.002);
    capture.values[1].push_back(8e6 + (i % 7) * 1e3);
    capture.values[2].push_back(8e6 - (i % 5) * 1e3);
  }
  capture::write_capture(dir + "/c.csv", capture);
  std::ofstream(dir + "/leakmon.yaml")
      << "drivers: [{name: bench, type: replay, path: c.csv, loop: true}]\n"
         "actuators: [{name: a, channels: {p1: p1, p2: p2}}]\n"
         "metrics: {port: 0}\n";

  NotifySocket notify(dir + "/notify.sock");
  ASSERT_TRUE(notify.ok());
  test::DaemonProcess daemon(
      {"run", "--config", dir + "/leakmon.yaml"}, dir + "/daemon.log",
      {{"NOTIFY_SOCKET", dir + "/notify.sock"}, {"WATCHDOG_USEC", "400000"}});
  ASSERT_TRUE(notify.wait_for("READY=1", 15s)) << daemon.log();
  EXPECT_NE(notify.messages.back().find("STATUS=running"), std::string::npos);
  ASSERT_TRUE(notify.wait_for("WATCHDOG=1", 5s)) << "no keep-alive while the loop runs";

  daemon.signal(SIGHUP);
  ASSERT_TRUE(notify.wait_for("RELOADING=1", 5s)) << daemon.log();
  ASSERT_TRUE(notify.wait_for("READY=1", 5s)) << "READY=1 must follow RELOADING=1";

  daemon.signal(SIGTERM);
  ASSERT_TRUE(notify.wait_for("STOPPING=1", 5s)) << daemon.log();
  EXPECT_EQ(daemon.wait(20s), 0) << daemon.log();
}

}  // namespace
}  // namespace leakmon
