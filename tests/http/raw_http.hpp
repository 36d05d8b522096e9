// Test helper: HTTP as raw bytes on a loopback socket, for the requests a well-behaved client
// (daemon::http_request) cannot send: oversized lines, hundreds of headers, bodies announced but
// never sent, bytes dripped one at a time.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace leakmon::test {

// A connected TCP socket to 127.0.0.1:`port`, or -1.
inline int connect_loopback(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Sends `request` and returns the answer's status line ("HTTP/1.1 431 ..."), "" when the server
// closed without one, "connect failed" when nobody listens. A server may answer and close before
// it has read everything (an oversized request), so a failed send only ends the sending.
inline std::string raw_http_status_line(int port, std::string_view request) {
  const int fd = connect_loopback(port);
  if (fd < 0) return "connect failed";
  while (!request.empty()) {
    const ssize_t n = ::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
    if (n <= 0) break;
    request.remove_prefix(static_cast<std::size_t>(n));
  }
  std::string reply;
  char buffer[4096];
  while (reply.find("\r\n") == std::string::npos) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 10000) <= 0) break;
    const ssize_t n = ::recv(fd, buffer, sizeof(buffer), 0);
    if (n <= 0) break;
    reply.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return reply.substr(0, reply.find("\r\n"));
}

}  // namespace leakmon::test
