// Logs written by real tools parse as those tools mean them: python-can's CanutilsLogWriter
// (its own reader is the oracle for every field) and can-utils' asc2log (Vector ASC in, candump
// log out), replayed through the canlog driver to the signal values that were encoded.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/canlog/candump.hpp"
#include "io/canlog/canlog_driver.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::io {
namespace {

int run(const std::string& command) { return std::system(command.c_str()); }

// Random frames of every kind written by python-can; python-can reads them back and prints
// time_ns, id, extended, fd, brs, remote, error, length, data hex per frame.
const char* const kPythonCanScript = R"PY(
import random, sys, can
random.seed(7)
path, expected = sys.argv[1], sys.argv[2]
writer = can.CanutilsLogWriter(path, channel="can0")
t = 1763740800.0
for k in range(400):
    t += random.choice([0.0001, 0.001, 0.002])
    kind = k % 5
    ext = random.random() < 0.4
    ident = random.randrange(1 << 29) if ext else random.randrange(1 << 11)
    if kind == 3:
        msg = can.Message(timestamp=t, arbitration_id=ident, is_extended_id=ext, is_fd=True,
                          bitrate_switch=random.random() < 0.5,
                          data=[random.randrange(256) for _ in range(random.choice([0, 5, 12, 20, 64]))])
    elif kind == 4 and k % 10 == 4:
        msg = can.Message(timestamp=t, arbitration_id=ident, is_extended_id=ext, is_remote_frame=True)
    else:
        msg = can.Message(timestamp=t, arbitration_id=ident, is_extended_id=ext,
                          data=[random.randrange(256) for _ in range(random.randrange(9))])
    writer.on_message_received(msg)
writer.stop()
with open(expected, "w") as out:
    for m in can.CanutilsLogReader(path):
        out.write("%d %d %d %d %d %d %d %d %s\n" % (round(m.timestamp * 1e6) * 1000, m.arbitration_id,
                  m.is_extended_id, m.is_fd, m.bitrate_switch, m.is_remote_frame, m.is_error_frame,
                  len(m.data), bytes(m.data).hex() or "-"))
)PY";

TEST(CandumpTools, PythonCanLogsParseAsPythonCanReadsThem) {
  const std::string dir = test::scratch_dir("candump_python_can");
  std::ofstream(dir + "/gen.py") << kPythonCanScript;
  ASSERT_EQ(
      run(test::python() + " " + dir + "/gen.py " + dir + "/bus.log " + dir + "/expected.txt"), 0);
  const canlog::CandumpLog log = canlog::read_candump_file(dir + "/bus.log");
  std::ifstream expected(dir + "/expected.txt");
  std::size_t n = 0;
  for (std::string line; std::getline(expected, line); ++n) {
    ASSERT_LT(n, log.frames.size());
    const can::CanFrame& f = log.frames[n].frame;
    std::istringstream in(line);
    long long time_ns = 0;
    unsigned id = 0, ext = 0, fd = 0, brs = 0, remote = 0, error = 0, length = 0;
    std::string hex;
    in >> time_ns >> id >> ext >> fd >> brs >> remote >> error >> length >> hex;
    ASSERT_EQ(log.frames[n].time_ns, time_ns) << line;
    EXPECT_EQ(f.id, id) << line;
    EXPECT_EQ(f.extended, ext != 0) << line;
    EXPECT_EQ(f.fd, fd != 0) << line;
    EXPECT_EQ((f.fd_flags & 1) != 0, brs != 0) << line;
    EXPECT_EQ(f.remote, remote != 0) << line;
    EXPECT_EQ(f.error, error != 0) << line;
    if (!f.remote) {
      ASSERT_EQ(f.length, length) << line;
      std::string mine;
      char byte[3];
      for (unsigned i = 0; i < f.length; ++i) {
        std::snprintf(byte, sizeof byte, "%02x", f.data[i]);
        mine += byte;
      }
      EXPECT_EQ(mine.empty() ? "-" : mine, hex) << line;
    }
  }
  EXPECT_EQ(n, 400U);
  EXPECT_EQ(log.frames.size(), n);
}

TEST(CandumpTools, Asc2logOutputReplaysToTheEncodedSignals) {
  if (run("command -v asc2log >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "asc2log (can-utils) is not installed";
  }
  const std::string dir = test::scratch_dir("candump_asc2log");
  // A Vector ASC trace: p1 (intel, 500 Pa/bit) on 0x101 and x (motorola, 1e-5 m/bit) on a 29-bit
  // id, 2 ms apart, as a rig logger would have recorded them.
  std::ofstream asc(dir + "/trace.asc");
  asc << "date Sat Nov 21 10:00:00.000 2026\nbase hex  timestamps absolute\n"
         "internal events logged\n// version 8.5.0\n"
         "Begin Triggerblock Sat Nov 21 10:00:00.000 2026\n   0.000000 Start of measurement\n";
  std::vector<double> expected_p1, expected_x;
  char line[160];
  for (int k = 0; k < 20; ++k) {
    const int p1_raw = 17000 + 37 * k;
    const int x_raw = -3000 + 311 * k;
    const auto x_bits = static_cast<unsigned>(x_raw) & 0xFFFFU;
    std::snprintf(line, sizeof line, "   %.6f 1  101             Rx   d 2 %02X %02X\n",
                  0.002 * (k + 1), p1_raw & 0xFF, p1_raw >> 8);
    asc << line;
    std::snprintf(line, sizeof line, "   %.6f 1  18FF0102x       Rx   d 3 %02X %02X 00\n",
                  0.002 * (k + 1) + 0.0005, x_bits >> 8, x_bits & 0xFF);
    asc << line;
    expected_p1.push_back(p1_raw * 500.0);
    expected_x.push_back(x_raw * 1e-5);
  }
  asc << "End TriggerBlock\n";
  asc.close();
  ASSERT_EQ(run("cd " + dir + " && asc2log -I trace.asc -O bus.log 2>/dev/null"), 0);
  std::ofstream(dir + "/replay.yaml")
      << "name: replay\ntype: canlog\nfile: bus.log\npace: fast\nperiod: 0.002\nsignals:\n"
         "  - channel: p1\n    id: 0x101\n    length: 16\n    factor: 500\n"
         "  - channel: x\n    id: 0x18FF0102\n    extended: true\n    start_bit: 7\n"
         "    length: 16\n    byte_order: motorola\n    signed: true\n    factor: 1.0e-5\n";
  auto driver = make_canlog_driver(config::ConfigNode::load_file(dir + "/replay.yaml"));
  driver->start();
  std::vector<double> v(2);
  std::vector<std::vector<double>> rows;
  while (driver->read(Tick{}, v) == ReadStatus::ok) rows.push_back(v);
  // Ticks fall 2 ms apart from the first frame: tick k sees p1 frame k and the x frame sent
  // 0.5 ms after p1 frame k-1; one more tick delivers the last x frame.
  ASSERT_EQ(rows.size(), expected_p1.size() + 1);
  EXPECT_TRUE(std::isnan(rows[0][1]));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(rows[k][0], expected_p1[std::min(k, expected_p1.size() - 1)]) << k;
    if (k > 0) {
      EXPECT_NEAR(rows[k][1], expected_x[k - 1], 1e-12) << k;
    }
  }
}

}  // namespace
}  // namespace leakmon::io
