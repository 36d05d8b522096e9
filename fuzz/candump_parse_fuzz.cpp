// Fuzzes the candump log parser, line by line and as a whole file. Invariants: a parsed frame
// never claims more bytes than its kind can carry, and an error's column lies on the line.
// fuzz-sources: io/canlog/candump.cpp
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "io/canlog/candump.hpp"

using namespace leakmon::io;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(start, end - start);
    canlog::LogRecord record;
    canlog::ParseProblem problem;
    switch (canlog::parse_candump_line(line, record, problem)) {
      case canlog::LineKind::frame: {
        const std::size_t limit = record.frame.fd ? can::kFdMaxLength : can::kClassicMaxLength;
        if (record.frame.length > limit) __builtin_trap();
        if (record.interface.empty() || record.time_ns < 0) __builtin_trap();
        break;
      }
      case canlog::LineKind::error:
        if (problem.column < 1 || problem.column > line.size() + 1) __builtin_trap();
        break;
      case canlog::LineKind::skip:
        break;
    }
    start = end + 1;
  }
  try {
    const canlog::CandumpLog log = canlog::parse_candump_text(text, "fuzz.log");
    for (std::size_t i = 1; i < log.frames.size(); ++i) {
      if (log.frames[i].time_ns < log.frames[i - 1].time_ns) __builtin_trap();
    }
  } catch (const std::runtime_error&) {
    // A malformed log is an error with a location, which is the point.
  }
  return 0;
}
