// The HTTP endpoint on one TCP address (127.0.0.1 by default) for Prometheus scrapes
// (GET /metrics), `leakmon status` (GET /status) and acknowledgement (POST /ack?actuator=NAME),
// served by libmicrohttpd: an epoll event loop on a small fixed pool of threads, so that an
// idle or slow client holds a socket, never a thread. Never touches the real-time threads.
//
// What a peer cannot do (HttpLimits): keep a request open past an absolute deadline (the
// library's own timeout restarts on every byte, so a watchdog closes connections whose request
// began too long ago), open more than a fixed number of connections, or send a request line,
// headers or body beyond fixed sizes (414, 431, 413 answers). The handler sees a parsed request
// (http/http_target.hpp) and returns a response; it knows nothing of the transport.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "http/http_target.hpp"

struct MHD_Daemon;

namespace leakmon::http {

struct HttpRequest {
  std::string method;                   // "GET", "HEAD", "POST", ...
  std::string path;                     // decoded, without the query
  std::string query;                    // after '?', undecoded
  std::vector<QueryParam> params = {};  // the query split at '&' and '=', decoded
  std::string accept = {};              // the Accept header, empty when absent
  std::string authorization = {};       // the Authorization header, empty when absent
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; version=0.0.4; charset=utf-8";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers = {};  // e.g. Allow on a 405
};

using HttpHandler = std::function<HttpResponse(const HttpRequest&)>;

struct HttpLimits {
  unsigned threads = 2;            // the worker pool: each runs its own epoll loop
  unsigned max_connections = 512;  // beyond this, new connections are closed at once
  int listen_backlog = 256;
  unsigned idle_timeout_s = 3;  // no byte for this long closes the connection
  // From accepting a connection (or finishing its previous request) to the response: a client
  // dripping a byte a second cannot hold a connection longer than this.
  std::chrono::milliseconds request_deadline{5000};
  std::size_t connection_memory_bytes = 32 * 1024;  // request line + headers (else 414 / 431)
  std::size_t max_headers = 100;                    // else 431
  std::size_t max_body_bytes = 4096;                // else 413; no endpoint takes a body
};

// What the endpoint has seen, for the metrics.
struct HttpCounters {
  std::atomic<std::uint64_t> requests{0};
  std::atomic<std::uint64_t> rejected{0};         // 400, 413, 431 answered before the handler
  std::atomic<std::uint64_t> deadline_closes{0};  // connections closed by the request deadline
  std::atomic<std::int64_t> open_connections{0};
};

class HttpEndpoint {
 public:
  // Binds and listens now (throws std::runtime_error naming the address on failure); port 0
  // picks a free port (see port()). `counters`, when given, must outlive the endpoint (the
  // daemon's metrics read them while the endpoint starts and stops).
  HttpEndpoint(const std::string& address, int port, HttpHandler handler, HttpLimits limits = {},
               HttpCounters* counters = nullptr);
  ~HttpEndpoint();
  HttpEndpoint(const HttpEndpoint&) = delete;
  HttpEndpoint& operator=(const HttpEndpoint&) = delete;

  int port() const { return port_; }
  const HttpLimits& limits() const { return limits_; }
  const HttpCounters& counters() const { return *counters_; }

  // One open connection (libmicrohttpd's socket context); public for the C callbacks only.
  struct Connection {
    int fd = -1;
    std::int64_t request_start_ns = 0;  // guarded by the endpoint's mutex
    bool closing = false;
    std::string raw_target;  // of the request being read (requests on a connection are serial)
  };
  void connection_started(Connection* connection);
  void connection_closed(Connection* connection);
  void request_finished(Connection* connection);
  HttpResponse answer(Connection* connection, const char* method, const char* url,
                      void* mhd_connection);

 private:
  void watch_deadlines();

  HttpLimits limits_;
  HttpHandler handler_;
  HttpCounters own_counters_;
  HttpCounters* counters_;
  int listen_fd_ = -1;
  int port_ = 0;
  MHD_Daemon* mhd_ = nullptr;
  std::mutex mutex_;  // guards connections_ and each Connection's deadline fields
  std::vector<Connection*> connections_;
  std::condition_variable stop_signal_;
  bool stopping_ = false;
  std::thread watchdog_;
};

// Client side, for `leakmon status` and `leakmon ack`: one request to address:port.
// Returns the status code and body; throws std::runtime_error when nothing answers.
HttpResponse http_request(const std::string& address, int port, const std::string& method,
                          const std::string& target);

// `text` with every byte outside RFC 3986's unreserved set as %XX, for a query value.
std::string percent_encode(std::string_view text);

}  // namespace leakmon::http
