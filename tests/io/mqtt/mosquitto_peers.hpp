// Debian's mosquitto broker and mosquitto_sub as child processes for the MQTT tests: a broker
// on a given local port with its configuration and persistence in a scratch directory, and a
// subscriber writing "topic payload" lines to a file.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tests/daemon/daemon_process.hpp"
#include "tests/io/modbus/peer_process.hpp"

namespace leakmon::test {

using namespace std::chrono_literals;

inline void write_file(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

inline std::vector<std::string> lines_of(const std::string& path) {
  std::vector<std::string> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) lines.push_back(line);
  return lines;
}

inline bool port_accepts(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
  ::close(fd);
  return ok;
}

// A mosquitto broker on `port` with its configuration, log and persistence under `dir`.
class Broker {
 public:
  Broker(std::string dir, int port, std::string extra = "allow_anonymous true\n")
      : dir_(std::move(dir)), port_(port) {
    write_file(dir_ + "/mosquitto.conf",
               "listener " + std::to_string(port_) + " 127.0.0.1\n" + extra +
                   "persistence true\nautosave_interval 1\n"
                   "autosave_on_changes true\npersistence_location " +
                   dir_ + "/\nuser root\nlog_dest stdout\nlog_type all\n");
    start();
  }
  void start() {
    process_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{"mosquitto", "-c", dir_ + "/mosquitto.conf"},
        dir_ + "/mosquitto." + std::to_string(starts_++) + ".log");
    if (!eventually([&] { return port_accepts(port_); }, 10s))
      throw std::runtime_error("mosquitto did not listen on " + std::to_string(port_));
  }
  // SIGKILL: the broker vanishes mid-conversation. It saved its sessions after every change
  // (autosave_on_changes with an interval of 1 change), so the test's subscriber keeps its
  // subscription across the restart and the broker queues what the daemon sends before the
  // subscriber is back (without it a loaded sanitizer run lost the daemon's first events after
  // the restart: published before mosquitto_sub had subscribed again).
  void kill() { process_->kill_and_wait(); }
  int port() const { return port_; }

 private:
  std::string dir_;
  int port_;
  int starts_ = 0;
  std::unique_ptr<ChildProcess> process_;
};

// mosquitto_sub on leakmon/#: "topic payload" per line in `path`. A persistent session (-c),
// so messages published while it reconnects are kept for it.
class Subscriber {
 public:
  // Returns once the subscription holds: a message published before mosquitto_sub has
  // subscribed is not delivered to it (a loaded sanitizer run lost the first of 200 events so).
  Subscriber(int port, std::string path, const std::string& id)
      : path_(std::move(path)),
        process_({"mosquitto_sub", "-h", "127.0.0.1", "-p", std::to_string(port), "-t", "leakmon/#",
                  "-v", "-q", "1", "-c", "-i", id},
                 path_) {
    const auto subscribed = [&] {
      ChildProcess probe({"mosquitto_pub", "-h", "127.0.0.1", "-p", std::to_string(port), "-t",
                          std::string(kProbeTopic), "-m", "1", "-q", "1"},
                         path_ + ".probe");
      probe.stop_and_wait(0, 5.0);  // signal 0: just wait for it
      return !messages(std::string(kProbeTopic)).empty();
    };
    if (!eventually(subscribed, 20s))
      throw std::runtime_error("mosquitto_sub did not subscribe on port " + std::to_string(port));
  }
  // The topic the constructor probes the subscription with (no test reads it).
  static constexpr std::string_view kProbeTopic = "leakmon/_subscribed";
  std::vector<std::pair<std::string, std::string>> messages(const std::string& suffix) const {
    return messages_in(path_, suffix);
  }

  // The messages on topics ending in `suffix` in a subscriber's file: (topic, payload).
  static std::vector<std::pair<std::string, std::string>> messages_in(const std::string& path,
                                                                      const std::string& suffix) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& line : lines_of(path)) {
      const auto space = line.find(' ');
      if (space == std::string::npos) continue;
      const std::string topic = line.substr(0, space);
      if (topic.size() >= suffix.size() &&
          topic.compare(topic.size() - suffix.size(), suffix.size(), suffix) == 0)
        out.emplace_back(topic, line.substr(space + 1));
    }
    return out;
  }

 private:
  std::string path_;
  ChildProcess process_;
};

// The retained status now: a fresh subscriber takes the retained message and leaves.
inline std::string retained_status(int port, const std::string& topic) {
  const std::string path =
      std::filesystem::temp_directory_path() / ("leakmon-status-" + std::to_string(::getpid()));
  ChildProcess probe({"mosquitto_sub", "-h", "127.0.0.1", "-p", std::to_string(port), "-t",
                      topic + "/status", "-C", "1", "-W", "3"},
                     path);
  probe.stop_and_wait(0, 5.0);  // signal 0: just wait for it
  std::string text = DaemonProcess::read_file(path);
  std::filesystem::remove(path);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return text;
}

}  // namespace leakmon::test
