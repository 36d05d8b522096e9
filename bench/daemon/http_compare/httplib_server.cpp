// cpp-httplib 0.11 answering GET /metrics with a body the size of the daemon's: its thread
// pool (8 threads, as many as the daemon would afford), 2 s read timeout.
#include <httplib.h>

#include <cstdlib>
#include <string>

int main(int, char** argv) {
  const std::string body(9000, 'm');
  httplib::Server server;
  server.new_task_queue = [] { return new httplib::ThreadPool(8); };
  server.set_read_timeout(2, 0);
  server.Get("/metrics", [&](const httplib::Request&, httplib::Response& r) {
    r.set_content(body, "text/plain");
  });
  server.listen("127.0.0.1", std::atoi(argv[1]));
}
