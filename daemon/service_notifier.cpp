#include "daemon/service_notifier.hpp"

#include <systemd/sd-daemon.h>

#include <cstdlib>

namespace leakmon::daemon {

ServiceNotifier::ServiceNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  active_ = socket != nullptr && *socket != '\0';
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_ = std::chrono::microseconds(usec);
}

void ServiceNotifier::send(const std::string& message) {
  if (active_) sd_notify(0, message.c_str());
}

void ServiceNotifier::ready(const std::string& status) { send("READY=1\nSTATUS=" + status); }

void ServiceNotifier::status(const std::string& status) { send("STATUS=" + status); }

void ServiceNotifier::reloading() { send("RELOADING=1\nSTATUS=reloading configuration"); }

void ServiceNotifier::stopping() { send("STOPPING=1\nSTATUS=stopping: draining and flushing"); }

void ServiceNotifier::watchdog() { send("WATCHDOG=1"); }

}  // namespace leakmon::daemon
