// The event log is always valid UTF-8 JSON, whatever the event text carries (configuration
// content quoted in a config_rejected message, device error text), and the log line has no raw
// escape sequences.
#include "pipeline/event_log.hpp"

#include <gtest/gtest.h>

#include <string>

#include "config/yaml_reader.hpp"

namespace leakmon::pipeline {
namespace {

// A strict check of the JSON string syntax and of UTF-8 validity of the whole line.
bool valid_utf8(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    unsigned code = 0;
    const std::size_t length = config::utf8_sequence(text, i, code);
    if (length == 0) return false;
    i += length;
  }
  return true;
}

bool no_raw_controls(const std::string& text) {
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x20 || byte == 0x7f) return false;
  }
  return true;
}

TEST(EventLog, InvalidUtf8AndControlCharactersAreEscaped) {
  io::Event event;
  event.kind = io::EventKind::config_rejected;
  event.message = std::string("bad \xff\xfe byte, ESC \x1b[2J, CSI \xc2\x9b, overlong \xc0\xaf, ") +
                  "surrogate \xed\xa0\x80, cut \xe2\x82, ok \xe2\x82\xac, quote \" backslash \\";
  const std::string json = to_json_line(event);
  EXPECT_TRUE(valid_utf8(json)) << json;
  EXPECT_TRUE(no_raw_controls(json)) << json;
  EXPECT_NE(json.find("bad \\ufffd\\ufffd byte"), std::string::npos) << json;
  EXPECT_NE(json.find("ESC \\u001b[2J"), std::string::npos) << json;
  EXPECT_NE(json.find("CSI \\u009b"), std::string::npos) << json;
  EXPECT_NE(json.find("overlong \\ufffd\\ufffd"), std::string::npos) << json;
  EXPECT_NE(json.find("surrogate \\ufffd\\ufffd\\ufffd"), std::string::npos) << json;
  EXPECT_NE(json.find("ok \xe2\x82\xac"), std::string::npos) << "valid UTF-8 stays as it is";
  EXPECT_NE(json.find("quote \\\" backslash \\\\"), std::string::npos) << json;

  const std::string line = to_log_line(event);
  EXPECT_TRUE(valid_utf8(line)) << line;
  EXPECT_TRUE(no_raw_controls(line)) << line;
  EXPECT_NE(line.find("ESC \\x1b[2J"), std::string::npos) << line;
}

TEST(EventLog, LifecycleAndRelearningFieldsAreWritten) {
  io::Event started;
  started.kind = io::EventKind::daemon_started;
  started.version = "1.2.3";
  started.config = "/etc/leakmon/leakmon.yaml";
  started.pid = 4242;
  EXPECT_EQ(to_json_line(started),
            "{\"event\": \"daemon_started\", \"version\": \"1.2.3\", \"config\": "
            "\"/etc/leakmon/leakmon.yaml\", \"pid\": 4242}");
  io::Event stopped;
  stopped.kind = io::EventKind::daemon_stopped;
  stopped.reason = "signal SIGTERM";
  stopped.uptime_s = 12.5;
  EXPECT_EQ(to_json_line(stopped),
            "{\"event\": \"daemon_stopped\", \"reason\": \"signal SIGTERM\", \"uptime_s\": 12.5}");
}

TEST(Printable, EscapesControlsReplacesInvalidBytesAndCuts) {
  EXPECT_EQ(config::printable("plain text"), "plain text");
  EXPECT_EQ(config::printable("a\x1b[31mb"), "a\\x1b[31mb");
  EXPECT_EQ(config::printable("x\xff"), "x\xef\xbf\xbd");
  EXPECT_EQ(config::printable("\xc2\x9b"), "\\x9b");
  EXPECT_EQ(config::printable(std::string(300, 'y'), 10), std::string(10, 'y') + "...");
}

}  // namespace
}  // namespace leakmon::pipeline
