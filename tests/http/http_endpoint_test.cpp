// The endpoint in-process (also under TSan: its event threads, the deadline watchdog and the
// handler meet here): the handler sees decoded parameters, HEAD drops the body, limits answer
// 431/413, and a client dripping bytes is cut off by the absolute request deadline.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>

#include "http/http_endpoint.hpp"
#include "tests/http/raw_http.hpp"

namespace leakmon::http {
namespace {

using namespace std::chrono_literals;

using test::connect_loopback;
using test::raw_http_status_line;

TEST(HttpEndpoint, HandlerSeesDecodedParametersAndLimitsAnswerFirst) {
  std::atomic<int> calls{0};
  std::string seen;  // written by the handler, read after the reply (happens-before via socket)
  std::mutex seen_mutex;
  HttpEndpoint endpoint("127.0.0.1", 0, [&](const HttpRequest& request) {
    ++calls;
    std::lock_guard lock(seen_mutex);
    seen = request.method + " " + request.path + " [" + request.query + "]";
    for (const auto& p : request.params) seen += " " + p.name + "=" + p.value;
    return HttpResponse{200, "text/plain", "body\n", {{"X-Test", "1"}}};
  });
  const HttpResponse ok =
      http_request("127.0.0.1", endpoint.port(), "GET", "/a%20b?x=1%2B1&y=a+b&&z");
  EXPECT_EQ(ok.status, 200);
  EXPECT_EQ(ok.body, "body\n");
  {
    std::lock_guard lock(seen_mutex);
    EXPECT_EQ(seen, "GET /a b [x=1%2B1&y=a+b&&z] x=1+1 y=a b z=");
  }
  const HttpResponse head = http_request("127.0.0.1", endpoint.port(), "HEAD", "/");
  EXPECT_EQ(head.status, 200);
  EXPECT_EQ(head.body, "");
  EXPECT_EQ(calls.load(), 2);

  EXPECT_EQ(http_request("127.0.0.1", endpoint.port(), "GET", "/?x=%4").status, 400);
  std::string many = "GET / HTTP/1.1\r\nHost: x\r\n";
  for (int i = 0; i < 200; ++i) many += "X-" + std::to_string(i) + ": y\r\n";
  EXPECT_EQ(raw_http_status_line(endpoint.port(), many + "\r\n").rfind("HTTP/1.1 431 ", 0), 0u);
  EXPECT_EQ(raw_http_status_line(endpoint.port(),
                                 "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 5000\r\n\r\n")
                .rfind("HTTP/1.1 413 ", 0),
            0u);
  EXPECT_EQ(calls.load(), 2);  // none of the refused requests reached the handler
  EXPECT_EQ(endpoint.counters().rejected.load(), 3u);
}

TEST(HttpEndpoint, DripFeedingClientIsCutOffByTheDeadline) {
  HttpLimits limits;
  limits.request_deadline = 600ms;
  limits.idle_timeout_s = 30;  // only the deadline can end the drip
  HttpEndpoint endpoint(
      "127.0.0.1", 0,
      [](const HttpRequest&) {
        return HttpResponse{200, "text/plain", "x"};
      },
      limits);
  const int fd = connect_loopback(endpoint.port());
  ASSERT_GE(fd, 0);
  const std::string request = "GET / HTTP/1.1\r\nHost: x\r\n\r\n";
  const auto start = std::chrono::steady_clock::now();
  bool closed = false;
  for (const char c : request) {
    if (::send(fd, &c, 1, MSG_NOSIGNAL) != 1) {
      closed = true;
      break;
    }
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 300) > 0) {
      char byte;
      if (::recv(fd, &byte, 1, 0) <= 0) {
        closed = true;
        break;
      }
    }
  }
  const auto lived = std::chrono::steady_clock::now() - start;
  ::close(fd);
  EXPECT_TRUE(closed) << "the whole request was dripped in without being cut off";
  // 27 bytes at 300 ms would take 8 s; the deadline ends it after 0.6 s plus the watchdog's
  // period (generous bound, not a timing assertion on the machine's speed).
  EXPECT_LT(lived, 6s);
  EXPECT_GE(endpoint.counters().deadline_closes.load(), 1u);
  // The endpoint still answers others.
  EXPECT_EQ(http_request("127.0.0.1", endpoint.port(), "GET", "/").status, 200);
}

}  // namespace
}  // namespace leakmon::http
