// can-utils' `candump -l` log format, one frame per line, as canplayer reads it:
//
//   (1700000000.123456) can0 123#DEADBEEF          classic frame, 3 hex digits = 11-bit id
//   (1700000000.123456) can0 12345678#00112233     8 hex digits = 29-bit id
//   (1700000000.123456) can0 123#R                 remote frame (optionally R0..R8: length)
//   (1700000000.123456) can0 123##1DEADBEEF        CAN FD: one flags nibble, then data
//   (1700000000.123456) can0 20000040#0000000000000000   8 digits with CAN_ERR_FLAG: error frame
//
// Data bytes may be separated by '.'; a classic frame may end in `_<dlc>` (len8_dlc); a
// trailing direction token `T` or `R` (candump -x) is accepted. Blank lines and lines starting
// with '#' are skipped. Timestamps are kept as integer nanoseconds, so a log replays exactly.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/can/frame.hpp"

namespace leakmon::io::canlog {

struct LogRecord {
  std::int64_t time_ns = 0;    // the log's timestamp (seconds since the epoch, as candump wrote it)
  std::string_view interface;  // points into the parsed line
  can::CanFrame frame;
};

struct ParseProblem {
  unsigned column = 0;  // 1-based
  const char* message = "";
};

enum class LineKind { frame, skip, error };

// Parses one line (without its newline). On `error`, `problem` says where and why.
// No allocation: suitable for fuzzing and for hot loops.
LineKind parse_candump_line(std::string_view line, LogRecord& record,
                            ParseProblem& problem) noexcept;

struct LoggedFrame {
  std::int64_t time_ns = 0;
  std::uint32_t line = 0;
  can::CanFrame frame;
};

struct CandumpLog {
  std::vector<LoggedFrame> frames;      // in file order
  std::vector<std::string> interfaces;  // distinct interface names, in order of appearance
};

// Reads a whole log. `interface` non-empty keeps only that interface's frames. Throws
// std::runtime_error `file:line:column: message` for a malformed line or timestamps that go
// backwards; a missing file names the file.
CandumpLog read_candump_file(const std::string& path, std::string_view interface = {});

// Parses log text held in memory; `source_name` stands in for the file name in errors.
CandumpLog parse_candump_text(std::string_view text, const std::string& source_name,
                              std::string_view interface = {});

}  // namespace leakmon::io::canlog
