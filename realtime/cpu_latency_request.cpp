#include "realtime/cpu_latency_request.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace leakmon::realtime {

CpuLatencyRequest::CpuLatencyRequest(std::int32_t max_wakeup_us, const std::string& device) {
  const int fd = ::open(device.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) {
    warning_ = fmt::format(
        "CPU wake-up latency request not held: cannot open {} ({}); idle CPUs may sleep deeply "
        "and add their exit latency to the loop's wake-ups (run as root, or DeviceAllow= it)",
        device, std::strerror(errno));
    return;
  }
  // The kernel takes the binary 32-bit value; the request lasts while the file stays open.
  if (::write(fd, &max_wakeup_us, sizeof max_wakeup_us) !=
      static_cast<ssize_t>(sizeof max_wakeup_us)) {
    warning_ = fmt::format("CPU wake-up latency request not held: writing {} us to {} failed ({})",
                           max_wakeup_us, device, std::strerror(errno));
    ::close(fd);
    return;
  }
  fd_ = fd;
}

CpuLatencyRequest::CpuLatencyRequest(CpuLatencyRequest&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), warning_(std::move(other.warning_)) {}

CpuLatencyRequest& CpuLatencyRequest::operator=(CpuLatencyRequest&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    warning_ = std::move(other.warning_);
  }
  return *this;
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace leakmon::realtime
