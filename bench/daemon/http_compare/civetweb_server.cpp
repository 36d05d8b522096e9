// civetweb 1.15 answering GET /metrics with a body the size of the daemon's: 8 worker threads,
// 2 s request timeout.
#include <civetweb.h>

#include <chrono>
#include <cstring>
#include <string>
#include <thread>

static std::string body(9000, 'm');

static int metrics(mg_connection* c, void*) {
  mg_send_http_ok(c, "text/plain", static_cast<long long>(body.size()));
  mg_write(c, body.data(), body.size());
  return 200;
}

int main(int, char** argv) {
  const std::string port = std::string("127.0.0.1:") + argv[1];
  const char* options[] = {"listening_ports",    port.c_str(), "num_threads", "8",
                           "request_timeout_ms", "2000",       nullptr};
  mg_init_library(0);
  mg_context* ctx = mg_start(nullptr, nullptr, options);
  mg_set_request_handler(ctx, "/metrics", metrics, nullptr);
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}
