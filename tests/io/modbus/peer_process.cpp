#include "tests/io/modbus/peer_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "tests/support/paths.hpp"

extern char** environ;

namespace leakmon::test {
namespace {

std::vector<std::string> server_argv(const ModbusServerOptions& options) {
  std::vector<std::string> argv = {python(), modbus_server_script(), "--ready-file",
                                   options.ready_file};
  if (!options.serial.empty()) {
    argv.insert(argv.end(), {"--serial", options.serial, "--parity", options.parity});
  } else {
    argv.insert(argv.end(), {"--tcp-port", std::to_string(options.tcp_port)});
  }
  if (!options.capture.empty())
    argv.insert(argv.end(), {"--capture", options.capture, "--map", options.map, "--rate",
                             std::to_string(options.rate_hz)});
  if (!options.capture.empty() && options.epoch > 0.0)
    argv.insert(argv.end(), {"--epoch", std::to_string(options.epoch)});
  argv.insert(argv.end(), {"--slow-seconds", std::to_string(options.slow_seconds)});
  if (options.garbage) argv.emplace_back("--garbage");
  return argv;
}

template <typename Ready>
void wait_for(Ready ready, const std::string& what) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!ready()) {
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("timed out waiting for " + what);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

}  // namespace

std::string modbus_server_script() { return source_dir() + "/tests/io/modbus/modbus_server.py"; }

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::string& log) {
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!log.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  const int error = posix_spawnp(&pid_, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error("cannot start " + argv[0]);
}

int ChildProcess::stop_and_wait(int signal, double seconds) {
  if (pid_ <= 0) return -1;
  ::kill(pid_, signal);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1e3));
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill_and_wait();
  return -1;
}

ChildProcess::~ChildProcess() { kill_and_wait(); }

void ChildProcess::send(int signal) const {
  if (pid_ > 0) ::kill(pid_, signal);
}

void ChildProcess::kill_and_wait() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGKILL);
  int status = 0;
  waitpid(pid_, &status, 0);
  pid_ = -1;
}

ModbusServer::ModbusServer(ModbusServerOptions options)
    : process_([&] {
        std::filesystem::remove(options.ready_file);
        return server_argv(options);
      }()) {
  wait_for([&] { return std::filesystem::exists(options.ready_file); },
           "the pymodbus server (" + options.ready_file + ")");
  std::ifstream(options.ready_file) >> port_;
}

void ModbusServer::toggle_slow() const { process_.send(SIGUSR1); }
void ModbusServer::toggle_exceptions() const { process_.send(SIGUSR2); }

PtyPair::PtyPair(const std::string& dir)
    : a_(dir + "/ttyA"),
      b_(dir + "/ttyB"),
      socat_({"socat", "pty,raw,echo=0,link=" + a_, "pty,raw,echo=0,link=" + b_}) {
  wait_for([&] { return std::filesystem::exists(a_) && std::filesystem::exists(b_); },
           "socat's pseudo-terminals");
}

}  // namespace leakmon::test
