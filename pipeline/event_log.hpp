// Built-in event sinks: the JSON-lines event log (FORMATS.md `leakmon replay` lines), the
// operator log (spdlog), and an in-memory list for in-process replay.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "io/event.hpp"
#include "io/event_json.hpp"

namespace leakmon::pipeline {

// The event log's JSON line (io/event_json.hpp, shared with the MQTT output).
using io::to_json_line;
// The one-line operator message for the log.
std::string to_log_line(const io::Event& event);

// Appends JSON lines to a file, flushed after every event (events are rare and must survive a
// crash). Opening creates parent directories.
class JsonlEventLog final : public io::EventSink {
 public:
  explicit JsonlEventLog(const std::string& path);
  ~JsonlEventLog() override;
  void publish(const io::Event& event) override;
  void flush() override;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

// Each event as a log line: warnings for alarms and faults, info for the rest.
class LogEventSink final : public io::EventSink {
 public:
  void publish(const io::Event& event) override;
};

class CollectingEventSink final : public io::EventSink {
 public:
  void publish(const io::Event& event) override { events.push_back(event); }
  std::vector<io::Event> events;
};

// `outputs:` type jsonl: `{name, type: jsonl, path}` — a second event log, e.g. on a share.
std::unique_ptr<io::EventSink> make_jsonl_output(const config::ConfigNode& node);

}  // namespace leakmon::pipeline
