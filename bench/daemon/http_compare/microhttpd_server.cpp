// libmicrohttpd 0.9.75 answering GET /metrics with a body the size of the daemon's, configured
// as http/http_endpoint.cpp is (epoll, 2 threads, 512 connections, 3 s inactivity timeout),
// without the endpoint's own deadline watchdog.
#include <microhttpd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

static std::string body(9000, 'm');

static MHD_Result answer(void*, MHD_Connection* c, const char*, const char*, const char*,
                         const char*, size_t*, void**) {
  MHD_Response* r =
      MHD_create_response_from_buffer(body.size(), body.data(), MHD_RESPMEM_PERSISTENT);
  const MHD_Result result = MHD_queue_response(c, 200, r);
  MHD_destroy_response(r);
  return result;
}

int main(int, char** argv) {
  MHD_start_daemon(MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL,
                   static_cast<uint16_t>(std::atoi(argv[1])), nullptr, nullptr, &answer, nullptr,
                   MHD_OPTION_THREAD_POOL_SIZE, 2u, MHD_OPTION_CONNECTION_LIMIT, 512u,
                   MHD_OPTION_CONNECTION_TIMEOUT, 3u, MHD_OPTION_END);
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}
