// A raw SocketCAN socket set up for leakmon: bound to one interface, filtered in the kernel to
// the configured identifiers, error frames enabled, CAN FD optional, every frame stamped by the
// kernel at reception (SO_TIMESTAMP) and the socket's drop counter attached (SO_RXQ_OVFL).
// receive() never blocks: the socket is non-blocking and read with MSG_DONTWAIT.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "io/can/frame.hpp"

struct can_filter;

namespace leakmon::io::can {

struct ReceivedFrame {
  CanFrame frame;
  std::int64_t realtime_ns = 0;  // kernel receive time, CLOCK_REALTIME
};

struct SocketOptions {
  std::string interface;
  bool fd = false;               // also receive CAN FD frames
  int receive_buffer_bytes = 0;  // SO_RCVBUF; 0 keeps the kernel default
};

class CanSocket {
 public:
  // Opens and binds; throws io::DriverError naming the interface and the failing call.
  CanSocket(const SocketOptions& options, std::span<const can_filter> filters);
  ~CanSocket();
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;

  enum class Result { frame, empty, failed };
  // The next queued frame, `empty` when none is queued, `failed` with errno in last_errno()
  // (e.g. ENETDOWN when the interface went down). No allocation, no blocking.
  Result receive(ReceivedFrame& out) noexcept;

  // The kernel's count of frames this socket dropped because its queue was full (SO_RXQ_OVFL),
  // as of the newest received frame.
  std::uint32_t kernel_drops() const { return kernel_drops_; }
  int last_errno() const { return last_errno_; }
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::uint32_t kernel_drops_ = 0;
  int last_errno_ = 0;
};

}  // namespace leakmon::io::can
