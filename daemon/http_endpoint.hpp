// A minimal HTTP/1.0 endpoint on one TCP address (127.0.0.1 by default) for Prometheus scrapes
// (GET /metrics), `leakmon status` (GET /status) and acknowledgement (POST /ack?actuator=NAME).
// One request per connection, served on the endpoint's own thread; never touches the
// real-time threads. Handlers return the response body; an empty optional is a 404.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <thread>

namespace leakmon::daemon {

struct HttpRequest {
  std::string method;  // "GET", "POST"
  std::string path;    // without the query
  std::string query;   // after '?', undecoded
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "text/plain; version=0.0.4; charset=utf-8";
  std::string body;
};

using HttpHandler = std::function<HttpResponse(const HttpRequest&)>;

class HttpEndpoint {
 public:
  // Binds and listens now (throws std::runtime_error naming the address on failure); port 0
  // picks a free port (see port()).
  HttpEndpoint(const std::string& address, int port, HttpHandler handler);
  ~HttpEndpoint();
  HttpEndpoint(const HttpEndpoint&) = delete;
  HttpEndpoint& operator=(const HttpEndpoint&) = delete;

  int port() const { return port_; }

 private:
  void serve();
  void answer(int connection);

  int listen_fd_ = -1;
  int port_ = 0;
  HttpHandler handler_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Client side, for `leakmon status` and `leakmon ack`: one request to 127.0.0.1:port.
// Returns the status code and body; throws std::runtime_error when nothing answers.
HttpResponse http_request(const std::string& address, int port, const std::string& method,
                          const std::string& target);

}  // namespace leakmon::daemon
