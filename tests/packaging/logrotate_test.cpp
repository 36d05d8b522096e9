// The event log's rotation as the package installs it (packaging/leakmon.logrotate), run by the
// real logrotate against the event log the daemon writes (pipeline::JsonlEventLog, the daemon's
// own sink): every event lands in exactly one file, whole, the live file continues at its new
// start after rotation (copytruncate and an append-mode file: no hole of NUL bytes), and the
// daemon needs no signal for it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "pipeline/event_log.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

io::Event numbered(int n) {
  io::Event event;
  event.kind = io::EventKind::driver_fault;
  event.channel = "daq";
  event.message = "event " + std::to_string(n);
  return event;
}

// logrotate as cron runs it, on the installed configuration with the log's path moved here.
void rotate(const std::string& dir, const std::string& log) {
  std::string conf = read_file(test::source_dir() + "/packaging/leakmon.logrotate");
  const std::string installed = "/var/lib/leakmon/events.jsonl";
  ASSERT_NE(conf.find(installed), std::string::npos) << conf;
  conf.replace(conf.find(installed), installed.size(), log);
  std::ofstream(dir + "/logrotate.conf") << conf;
  std::filesystem::permissions(dir + "/logrotate.conf", std::filesystem::perms::owner_read |
                                                            std::filesystem::perms::owner_write);
  const std::string command = "/usr/sbin/logrotate --force --state " + dir + "/logrotate.state " +
                              dir + "/logrotate.conf > " + dir + "/logrotate.log 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_file(dir + "/logrotate.log");
}

TEST(EventLogRotation, EveryEventIsKeptWholeAndTheDaemonWritesOnWithoutASignal) {
  const std::string dir = test::scratch_dir("event_log_rotation");
  const std::string log = dir + "/events.jsonl";
  pipeline::JsonlEventLog sink(log);
  for (int n = 0; n < 3; ++n) sink.publish(numbered(n));

  rotate(dir, log);
  for (int n = 3; n < 5; ++n) sink.publish(numbered(n));
  rotate(dir, log);  // the second rotation compresses the first (delaycompress)
  sink.publish(numbered(5));

  const std::string live = read_file(log);
  ASSERT_FALSE(live.empty());
  EXPECT_EQ(live.find('\0'), std::string::npos) << "a hole: the daemon wrote at its old offset";
  EXPECT_EQ(live.front(), '{') << live;
  const auto live_lines = lines_of(live);
  ASSERT_EQ(live_lines.size(), 1u) << live;
  EXPECT_NE(live_lines[0].find("event 5"), std::string::npos) << live;

  const auto previous = lines_of(read_file(log + ".1"));
  ASSERT_EQ(previous.size(), 2u);
  EXPECT_NE(previous[0].find("event 3"), std::string::npos);
  EXPECT_NE(previous[1].find("event 4"), std::string::npos);
  ASSERT_TRUE(std::filesystem::exists(log + ".2.gz")) << "the older rotation is compressed";
  const std::string oldest_text = dir + "/oldest.txt";
  ASSERT_EQ(std::system(("gzip -dc " + log + ".2.gz > " + oldest_text).c_str()), 0);
  const auto oldest = lines_of(read_file(oldest_text));
  ASSERT_EQ(oldest.size(), 3u);
  for (int n = 0; n < 3; ++n) {
    EXPECT_NE(oldest[static_cast<std::size_t>(n)].find("event " + std::to_string(n)),
              std::string::npos);
  }
}

}  // namespace
}  // namespace leakmon
