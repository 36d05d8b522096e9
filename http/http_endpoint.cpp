#include "http/http_endpoint.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <stdexcept>

namespace leakmon::http {
namespace {

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

sockaddr_in make_address(const std::string& address, int port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  if (inet_pton(AF_INET, address.c_str(), &addr.sin_addr) != 1) {
    throw std::runtime_error(fmt::format("'{}' is not an IPv4 address", address));
  }
  return addr;
}

void send_all(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n <= 0) return;
    data.remove_prefix(static_cast<std::size_t>(n));
  }
}

HttpEndpoint::Connection* connection_of(MHD_Connection* connection) {
  const MHD_ConnectionInfo* info =
      MHD_get_connection_info(connection, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  return info == nullptr ? nullptr : static_cast<HttpEndpoint::Connection*>(info->socket_context);
}

void notify_connection(void* cls, MHD_Connection* connection, void** socket_context,
                       MHD_ConnectionNotificationCode code) {
  auto* endpoint = static_cast<HttpEndpoint*>(cls);
  if (code == MHD_CONNECTION_NOTIFY_STARTED) {
    auto* record = new (std::nothrow) HttpEndpoint::Connection;
    if (record == nullptr) return;
    const MHD_ConnectionInfo* info =
        MHD_get_connection_info(connection, MHD_CONNECTION_INFO_CONNECTION_FD);
    record->fd = info == nullptr ? -1 : info->connect_fd;
    endpoint->connection_started(record);
    *socket_context = record;
  } else if (code == MHD_CONNECTION_NOTIFY_CLOSED && *socket_context != nullptr) {
    // libmicrohttpd notifies before it closes the socket, so the watchdog (which shuts down
    // sockets under the same mutex) never touches a descriptor number that was reused.
    auto* record = static_cast<HttpEndpoint::Connection*>(*socket_context);
    endpoint->connection_closed(record);
    delete record;
    *socket_context = nullptr;
  }
}

void* remember_target(void* /*cls*/, const char* uri, MHD_Connection* connection) {
  try {
    if (auto* record = connection_of(connection)) record->raw_target = uri == nullptr ? "" : uri;
  } catch (...) {  // bad_alloc: the request then gets a 400 for an empty target
  }
  return nullptr;
}

void request_completed(void* cls, MHD_Connection* connection, void** /*request_context*/,
                       MHD_RequestTerminationCode /*code*/) {
  if (auto* record = connection_of(connection)) {
    static_cast<HttpEndpoint*>(cls)->request_finished(record);
  }
}

MHD_Result queue(MHD_Connection* connection, const HttpResponse& answer) {
  MHD_Response* response = MHD_create_response_from_buffer(
      answer.body.size(), const_cast<char*>(answer.body.data()), MHD_RESPMEM_MUST_COPY);
  if (response == nullptr) return MHD_NO;
  MHD_add_response_header(response, MHD_HTTP_HEADER_CONTENT_TYPE, answer.content_type.c_str());
  for (const auto& [name, value] : answer.headers) {
    MHD_add_response_header(response, name.c_str(), value.c_str());
  }
  const MHD_Result result =
      MHD_queue_response(connection, static_cast<unsigned int>(answer.status), response);
  MHD_destroy_response(response);
  return result;
}

MHD_Result access_handler(void* cls, MHD_Connection* connection, const char* url,
                          const char* method, const char* /*version*/, const char* /*upload_data*/,
                          std::size_t* /*upload_data_size*/, void** /*request_context*/) {
  auto* endpoint = static_cast<HttpEndpoint*>(cls);
  try {
    // Answered on the first call, once the head is read: no endpoint reads a body, and a
    // queued response tells libmicrohttpd to close rather than read what follows.
    return queue(connection, endpoint->answer(connection_of(connection), method, url, connection));
  } catch (...) {
    return MHD_NO;  // out of memory: drop the connection
  }
}

HttpResponse plain(int status, std::string body) {
  return HttpResponse{
      status, "text/plain; charset=utf-8", std::move(body), {{"Connection", "close"}}};
}

}  // namespace

HttpEndpoint::HttpEndpoint(const std::string& address, int port, HttpHandler handler,
                           HttpLimits limits, HttpCounters* counters)
    : limits_(limits),
      handler_(std::move(handler)),
      counters_(counters != nullptr ? counters : &own_counters_) {
  const sockaddr_in addr = make_address(address, port);
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listen_fd_ < 0) throw std::runtime_error(fmt::format("socket: {}", std::strerror(errno)));
  const int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(listen_fd_, limits_.listen_backlog) != 0) {
    const std::string error = std::strerror(errno);
    ::close(listen_fd_);
    throw std::runtime_error(
        fmt::format("metrics endpoint {}:{}: cannot listen: {}", address, port, error));
  }
  sockaddr_in bound{};
  socklen_t length = sizeof(bound);
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&bound), &length);
  port_ = ntohs(bound.sin_port);

  mhd_ = MHD_start_daemon(
      MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_EPOLL, 0, nullptr, nullptr, &access_handler, this,
      MHD_OPTION_LISTEN_SOCKET, listen_fd_, MHD_OPTION_THREAD_POOL_SIZE, limits_.threads,
      MHD_OPTION_CONNECTION_LIMIT, limits_.max_connections, MHD_OPTION_CONNECTION_TIMEOUT,
      limits_.idle_timeout_s, MHD_OPTION_CONNECTION_MEMORY_LIMIT, limits_.connection_memory_bytes,
      MHD_OPTION_NOTIFY_CONNECTION, &notify_connection, this, MHD_OPTION_NOTIFY_COMPLETED,
      &request_completed, this, MHD_OPTION_URI_LOG_CALLBACK, &remember_target, this,
      MHD_OPTION_END);
  if (mhd_ == nullptr) {
    ::close(listen_fd_);
    throw std::runtime_error(
        fmt::format("metrics endpoint {}:{}: libmicrohttpd did not start", address, port));
  }
  watchdog_ = std::thread([this] { watch_deadlines(); });
}

HttpEndpoint::~HttpEndpoint() {
  MHD_stop_daemon(mhd_);  // closes every connection and the listening socket
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  stop_signal_.notify_all();
  watchdog_.join();
}

void HttpEndpoint::connection_started(Connection* connection) {
  std::lock_guard lock(mutex_);
  connection->request_start_ns = steady_now_ns();
  connections_.push_back(connection);
  counters_->open_connections.fetch_add(1, std::memory_order_relaxed);
}

void HttpEndpoint::connection_closed(Connection* connection) {
  std::lock_guard lock(mutex_);
  std::erase(connections_, connection);
  counters_->open_connections.fetch_sub(1, std::memory_order_relaxed);
}

void HttpEndpoint::request_finished(Connection* connection) {
  std::lock_guard lock(mutex_);
  connection->request_start_ns = steady_now_ns();
}

void HttpEndpoint::watch_deadlines() {
  const std::int64_t deadline_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(limits_.request_deadline).count();
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    stop_signal_.wait_for(lock, std::chrono::milliseconds(100));
    const std::int64_t now = steady_now_ns();
    for (Connection* connection : connections_) {
      if (connection->closing || connection->fd < 0) continue;
      if (now - connection->request_start_ns <= deadline_ns) continue;
      // Counted first, so whoever sees the connection end also sees the count. The event loop
      // sees the hang-up and closes the connection itself.
      counters_->deadline_closes.fetch_add(1, std::memory_order_relaxed);
      connection->closing = true;
      ::shutdown(connection->fd, SHUT_RDWR);
    }
  }
}

HttpResponse HttpEndpoint::answer(Connection* connection, const char* method, const char* url,
                                  void* mhd_connection) {
  auto* peer = static_cast<MHD_Connection*>(mhd_connection);
  counters_->requests.fetch_add(1, std::memory_order_relaxed);
  const int headers = MHD_get_connection_values(peer, MHD_HEADER_KIND, nullptr, nullptr);
  if (headers < 0 || static_cast<std::size_t>(headers) > limits_.max_headers) {
    counters_->rejected.fetch_add(1, std::memory_order_relaxed);
    return plain(MHD_HTTP_REQUEST_HEADER_FIELDS_TOO_LARGE,
                 fmt::format("more than {} header fields\n", limits_.max_headers));
  }
  if (const char* length =
          MHD_lookup_connection_value(peer, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH)) {
    std::uint64_t bytes = 0;
    const char* end = length + std::strlen(length);
    const auto [ptr, error] = std::from_chars(length, end, bytes);
    if (error != std::errc{} || ptr != end || bytes > limits_.max_body_bytes) {
      counters_->rejected.fetch_add(1, std::memory_order_relaxed);
      return plain(MHD_HTTP_CONTENT_TOO_LARGE,
                   fmt::format("request bodies are limited to {} bytes\n", limits_.max_body_bytes));
    }
  }
  const std::string raw = connection != nullptr && !connection->raw_target.empty()
                              ? connection->raw_target
                              : std::string(url == nullptr ? "" : url);
  RequestTargetResult target = parse_request_target(raw);
  if (!target.target) {
    counters_->rejected.fetch_add(1, std::memory_order_relaxed);
    return plain(MHD_HTTP_BAD_REQUEST, fmt::format("bad request target: {}\n", target.error));
  }
  HttpRequest request;
  request.method = method == nullptr ? "" : method;
  request.path = std::move(target.target->path);
  request.query = std::move(target.target->query);
  request.params = std::move(target.target->params);
  if (const char* accept = MHD_lookup_connection_value(peer, MHD_HEADER_KIND, "Accept")) {
    request.accept = accept;
  }
  if (const char* authorization =
          MHD_lookup_connection_value(peer, MHD_HEADER_KIND, "Authorization")) {
    request.authorization = authorization;
  }
  try {
    return handler_(request);
  } catch (const std::exception& e) {
    return plain(MHD_HTTP_INTERNAL_SERVER_ERROR, fmt::format("error: {}\n", e.what()));
  }
}

std::string percent_encode(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (std::isalnum(byte) != 0 || c == '-' || c == '.' || c == '_' || c == '~') {
      out += c;
    } else {
      out += fmt::format("%{:02X}", static_cast<unsigned>(byte));
    }
  }
  return out;
}

HttpResponse http_request(const std::string& address, int port, const std::string& method,
                          const std::string& target) {
  const sockaddr_in addr = make_address(address, port);
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error(fmt::format("socket: {}", std::strerror(errno)));
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    const std::string error = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error(
        fmt::format("no leakmon daemon answers on {}:{} ({})", address, port, error));
  }
  send_all(fd, fmt::format("{} {} HTTP/1.0\r\nHost: {}\r\nContent-Length: 0\r\n\r\n", method,
                           target, address));
  std::string reply;
  char buffer[4096];
  while (true) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 5000) <= 0) break;
    const ssize_t n = ::recv(fd, buffer, sizeof(buffer), 0);
    if (n <= 0) break;
    reply.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  HttpResponse response;
  const auto space = reply.find(' ');
  const auto body = reply.find("\r\n\r\n");
  if (space == std::string::npos || body == std::string::npos) {
    throw std::runtime_error(fmt::format("{}:{}: not an HTTP answer", address, port));
  }
  response.status = std::atoi(reply.c_str() + space + 1);
  response.body = reply.substr(body + 4);
  // The headers the callers look at.
  const std::string head = reply.substr(0, body);
  for (std::size_t line = head.find("\r\n"); line != std::string::npos;
       line = head.find("\r\n", line + 2)) {
    const std::size_t end = head.find("\r\n", line + 2);
    const std::string field =
        head.substr(line + 2, end == std::string::npos ? std::string::npos : end - line - 2);
    const std::size_t colon = field.find(':');
    if (colon == std::string::npos) continue;
    std::string value = field.substr(colon + 1);
    while (!value.empty() && value.front() == ' ') value.erase(0, 1);
    std::string name = field.substr(0, colon);
    for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (name == "content-type") {
      response.content_type = value;
    } else {
      response.headers.emplace_back(name, value);
    }
  }
  return response;
}

}  // namespace leakmon::http
