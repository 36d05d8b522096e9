// Real peers for the Modbus tests, run as child processes: the pymodbus server of
// modbus_server.py (TCP or serial) and a socat pseudo-terminal pair standing in for an RS-485
// line. Each is killed and reaped when its object goes away.
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

namespace leakmon::test {

class ChildProcess {
 public:
  // `log`: file for the child's stdout and stderr; empty keeps the test's.
  explicit ChildProcess(const std::vector<std::string>& argv, const std::string& log = "");
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  void send(int signal) const;
  void kill_and_wait();  // SIGKILL: the peer vanishes without closing anything politely
  // Sends `signal` and waits up to `seconds` for the exit; the exit code, or -1 (then killed).
  int stop_and_wait(int signal, double seconds);
  bool running() const { return pid_ > 0; }

 private:
  pid_t pid_ = -1;
};

struct ModbusServerOptions {
  std::string ready_file;    // where the server writes its port once it listens
  int tcp_port = 0;          // 0: any free port
  std::string serial;        // serial device instead of TCP
  std::string parity = "N";  // serial parity; Linux pseudo-terminals refuse E and O (EINVAL)
  std::string capture;       // capture CSV to follow
  std::string map;           // name:register:address:type:order:scale:offset,...
  double rate_hz = 500.0;
  double epoch = 0.0;  // wall-clock time of the capture's row 0 (s since 1970); 0: server start
  double slow_seconds = 0.2;
  bool garbage = false;
};

class ModbusServer {
 public:
  explicit ModbusServer(ModbusServerOptions options);  // returns once the server listens
  int port() const { return port_; }
  void kill() { process_.kill_and_wait(); }
  void toggle_slow() const;        // SIGUSR1
  void toggle_exceptions() const;  // SIGUSR2

 private:
  ChildProcess process_;
  int port_ = 0;
};

// A connected pair of pseudo-terminals: what one side writes the other reads.
class PtyPair {
 public:
  explicit PtyPair(const std::string& dir);  // links dir/ttyA and dir/ttyB
  const std::string& a() const { return a_; }
  const std::string& b() const { return b_; }

 private:
  std::string a_;
  std::string b_;
  ChildProcess socat_;
};

std::string modbus_server_script();

}  // namespace leakmon::test
