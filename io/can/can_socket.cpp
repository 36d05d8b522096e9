#include "io/can/can_socket.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "io/driver.hpp"

namespace leakmon::io::can {
namespace {

[[noreturn]] void fail(const SocketOptions& options, const std::string& what, int error) {
  throw DriverError("CAN interface '" + options.interface + "': " + what + ": " +
                    std::strerror(error));
}

void set_option(int fd, const SocketOptions& options, int level, int name, const void* value,
                socklen_t size, const char* what) {
  if (setsockopt(fd, level, name, value, size) != 0) fail(options, what, errno);
}

}  // namespace

CanSocket::CanSocket(const SocketOptions& options, std::span<const can_filter> filters) {
  if (options.interface.empty() || options.interface.size() >= IFNAMSIZ) {
    throw DriverError("CAN interface name '" + options.interface + "' is empty or too long");
  }
  fd_ = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0)
    fail(options, "socket(PF_CAN, SOCK_RAW, CAN_RAW) (does this kernel have CAN?)", errno);
  try {
    const int on = 1;
    if (options.fd) {
      set_option(fd_, options, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on,
                 "enabling CAN FD frames (CAN_RAW_FD_FRAMES)");
    }
    set_option(fd_, options, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
               static_cast<socklen_t>(filters.size() * sizeof(can_filter)), "CAN_RAW_FILTER");
    const can_err_mask_t errors = CAN_ERR_MASK;
    set_option(fd_, options, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors,
               "CAN_RAW_ERR_FILTER");
    set_option(fd_, options, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on, "SO_TIMESTAMP");
    set_option(fd_, options, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on, "SO_RXQ_OVFL");
    if (options.receive_buffer_bytes > 0) {
      set_option(fd_, options, SOL_SOCKET, SO_RCVBUF, &options.receive_buffer_bytes,
                 sizeof options.receive_buffer_bytes, "SO_RCVBUF");
    }
    const unsigned index = if_nametoindex(options.interface.c_str());
    if (index == 0) fail(options, "no such interface", errno);
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = static_cast<int>(index);
    if (bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      fail(options, "bind", errno);
    }
  } catch (...) {
    close(fd_);
    throw;
  }
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) close(fd_);
}

CanSocket::Result CanSocket::receive(ReceivedFrame& out) noexcept {
  canfd_frame raw{};
  iovec io{&raw, sizeof raw};
  // Room for the timestamp and the drop counter; aligned as cmsghdr requires.
  alignas(cmsghdr) unsigned char
      control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t))];
  msghdr message{};
  message.msg_iov = &io;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof control;
  const ssize_t received = recvmsg(fd_, &message, MSG_DONTWAIT);
  if (received < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK) return Result::empty;
    last_errno_ = errno;
    return Result::failed;
  }
  if (received != CAN_MTU && received != CANFD_MTU) {
    last_errno_ = EPROTO;
    return Result::failed;
  }
  out.realtime_ns = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMP) {
      timeval stamp{};
      std::memcpy(&stamp, CMSG_DATA(c), sizeof stamp);
      out.realtime_ns =
          std::int64_t{stamp.tv_sec} * 1'000'000'000 + std::int64_t{stamp.tv_usec} * 1000;
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      std::memcpy(&kernel_drops_, CMSG_DATA(c), sizeof kernel_drops_);
    }
  }
  CanFrame& frame = out.frame;
  frame.fd = received == CANFD_MTU;
  frame.error = (raw.can_id & CAN_ERR_FLAG) != 0;
  frame.extended = !frame.error && (raw.can_id & CAN_EFF_FLAG) != 0;
  frame.remote = !frame.fd && (raw.can_id & CAN_RTR_FLAG) != 0;
  frame.id = raw.can_id & (frame.error      ? CAN_ERR_MASK
                           : frame.extended ? CAN_EFF_MASK
                                            : CAN_SFF_MASK);
  frame.fd_flags = frame.fd ? raw.flags : 0;
  frame.length = raw.len <= (frame.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN) ? raw.len : 0;
  std::memcpy(frame.data.data(), raw.data, frame.length);
  return Result::frame;
}

}  // namespace leakmon::io::can
