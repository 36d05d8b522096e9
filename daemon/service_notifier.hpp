// The systemd notification protocol (sd_notify(3)) for a Type=notify service: READY, STATUS,
// RELOADING, STOPPING and WATCHDOG datagrams to $NOTIFY_SOCKET. Outside systemd (no
// NOTIFY_SOCKET) every call is a no-op.
#pragma once

#include <chrono>
#include <string>

namespace leakmon::daemon {

class ServiceNotifier {
 public:
  ServiceNotifier();

  bool active() const { return active_; }
  void ready(const std::string& status);
  void status(const std::string& status);
  void reloading();
  void stopping();
  void watchdog();
  // WatchdogSec from the environment ($WATCHDOG_USEC for this process), zero when none.
  std::chrono::microseconds watchdog_interval() const { return watchdog_; }

 private:
  void send(const std::string& message);
  bool active_ = false;
  std::chrono::microseconds watchdog_{0};
};

}  // namespace leakmon::daemon
