#include "io/canlog/candump.hpp"

#include <linux/can.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace leakmon::io::canlog {
namespace {

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Keeps seconds * 1e9 inside int64 (the year 2255).
constexpr std::int64_t kMaxSeconds = 9'000'000'000;

bool is_space(char c) noexcept { return c == ' ' || c == '\t' || c == '\r'; }

// A cursor over one line that remembers where a problem was found.
class Cursor {
 public:
  explicit Cursor(std::string_view line) : line_(line) {}
  bool done() const { return pos_ >= line_.size(); }
  char peek() const { return done() ? '\0' : line_[pos_]; }
  void advance() { ++pos_; }
  std::size_t pos() const { return pos_; }
  std::string_view line() const { return line_; }
  void skip_spaces() {
    while (!done() && is_space(line_[pos_])) ++pos_;
  }
  LineKind fail(ParseProblem& problem, const char* message) const {
    return fail_at(pos_, problem, message);
  }
  LineKind fail_at(std::size_t pos, ParseProblem& problem, const char* message) const {
    problem.column = static_cast<unsigned>(pos + 1);
    problem.message = message;
    return LineKind::error;
  }
  bool reject(ParseProblem& problem, const char* message) const {
    fail(problem, message);
    return false;
  }

 private:
  std::string_view line_;
  std::size_t pos_ = 0;
};

// `(seconds.fraction)`: integer arithmetic, fraction of 1..9 digits.
bool parse_time(Cursor& c, std::int64_t& time_ns, ParseProblem& problem) {
  if (c.peek() != '(') return c.reject(problem, "expected '(' opening the timestamp");
  c.advance();
  std::int64_t seconds = 0;
  int digits = 0;
  while (c.peek() >= '0' && c.peek() <= '9') {
    seconds = seconds * 10 + (c.peek() - '0');
    if (++digits > 10 || seconds > kMaxSeconds) {
      return c.reject(problem, "timestamp seconds out of range");
    }
    c.advance();
  }
  if (digits == 0) return c.reject(problem, "expected the timestamp's seconds");
  if (c.peek() != '.') return c.reject(problem, "expected '.' in the timestamp (sec.usec)");
  c.advance();
  std::int64_t fraction = 0;
  int fraction_digits = 0;
  while (c.peek() >= '0' && c.peek() <= '9') {
    if (++fraction_digits > 9)
      return c.reject(problem, "timestamp fraction has more than 9 digits");
    fraction = fraction * 10 + (c.peek() - '0');
    c.advance();
  }
  if (fraction_digits == 0) return c.reject(problem, "expected the timestamp's fraction");
  for (int i = fraction_digits; i < 9; ++i) fraction *= 10;
  if (c.peek() != ')') return c.reject(problem, "expected ')' closing the timestamp");
  c.advance();
  time_ns = seconds * 1'000'000'000 + fraction;
  return true;
}

// Data bytes as hex pairs, optionally separated by '.', up to `max_bytes`.
bool parse_data(Cursor& c, can::CanFrame& frame, std::size_t max_bytes, ParseProblem& problem) {
  frame.length = 0;
  while (!c.done() && !is_space(c.peek()) && c.peek() != '_') {
    if (c.peek() == '.') {
      c.advance();
      continue;
    }
    const int high = hex_value(c.peek());
    if (high < 0) return c.reject(problem, "expected a hex digit in the data");
    if (frame.length >= max_bytes) {
      return c.reject(problem, max_bytes == can::kClassicMaxLength
                                   ? "more than 8 data bytes in a classic CAN frame"
                                   : "more than 64 data bytes in a CAN FD frame");
    }
    c.advance();
    const int low = hex_value(c.peek());
    if (low < 0) {
      return c.reject(problem, c.done() || is_space(c.peek())
                                   ? "odd number of hex digits in the data"
                                   : "expected a hex digit in the data");
    }
    c.advance();
    frame.data[frame.length++] = static_cast<std::uint8_t>(high * 16 + low);
  }
  return true;
}

}  // namespace

LineKind parse_candump_line(std::string_view line, LogRecord& record,
                            ParseProblem& problem) noexcept {
  Cursor c(line);
  c.skip_spaces();
  if (c.done() || c.peek() == '#') return LineKind::skip;
  record = LogRecord{};
  if (!parse_time(c, record.time_ns, problem)) return LineKind::error;
  if (!is_space(c.peek())) return c.fail(problem, "expected a space after the timestamp");
  c.skip_spaces();
  const std::size_t interface_start = c.pos();
  while (!c.done() && !is_space(c.peek())) c.advance();
  if (c.pos() == interface_start) return c.fail(problem, "expected the interface name");
  record.interface = line.substr(interface_start, c.pos() - interface_start);
  c.skip_spaces();

  // Identifier: 3 hex digits (11-bit) or 8 (29-bit, or an error frame with CAN_ERR_FLAG).
  const std::size_t id_start = c.pos();
  std::uint32_t id = 0;
  while (hex_value(c.peek()) >= 0) {
    if (c.pos() - id_start >= 8) return c.fail(problem, "CAN id has more than 8 hex digits");
    id = id * 16 + static_cast<std::uint32_t>(hex_value(c.peek()));
    c.advance();
  }
  const std::size_t id_digits = c.pos() - id_start;
  if (id_digits == 0) return c.fail(problem, "expected a CAN id (3 or 8 hex digits) before '#'");
  if (c.peek() != '#') return c.fail(problem, "expected '#' after the CAN id");
  can::CanFrame& frame = record.frame;
  if (id_digits == 3) {
    if (id > can::kStandardIdMask) {
      return c.fail_at(id_start, problem, "standard CAN id above 0x7FF");
    }
    frame.id = id;
  } else if (id_digits == 8) {
    frame.error = (id & CAN_ERR_FLAG) != 0;
    frame.extended = !frame.error;
    frame.id = id & (frame.error ? CAN_ERR_MASK : CAN_EFF_MASK);
    if (!frame.error && (id & ~CAN_EFF_MASK) != 0) {
      return c.fail_at(id_start, problem, "extended CAN id has flag bits set above 0x1FFFFFFF");
    }
  } else {
    return c.fail_at(id_start, problem, "CAN id must have 3 hex digits (11-bit) or 8 (29-bit)");
  }
  c.advance();  // '#'

  if (c.peek() == '#') {  // CAN FD
    if (frame.error) return c.fail(problem, "an error frame cannot be a CAN FD frame");
    c.advance();
    const int flags = hex_value(c.peek());
    if (flags < 0) return c.fail(problem, "expected the CAN FD flags nibble after '##'");
    c.advance();
    frame.fd = true;
    frame.fd_flags = static_cast<std::uint8_t>(flags);
    if (!parse_data(c, frame, can::kFdMaxLength, problem)) return LineKind::error;
  } else if (c.peek() == 'R' || c.peek() == 'r') {
    if (frame.error) return c.fail(problem, "an error frame cannot be a remote frame");
    c.advance();
    frame.remote = true;
    if (!c.done() && !is_space(c.peek())) {
      const int length = hex_value(c.peek());
      if (length < 0 || length > 8) return c.fail(problem, "remote frame length must be 0..8");
      frame.length = static_cast<std::uint8_t>(length);
      c.advance();
      if (c.peek() == '_') {
        c.advance();
        const int dlc = hex_value(c.peek());
        if (length != 8 || dlc < 9) return c.fail(problem, "raw DLC must be 9..F after length 8");
        c.advance();
      }
    }
  } else {
    if (!parse_data(c, frame, can::kClassicMaxLength, problem)) return LineKind::error;
    if (c.peek() == '_') {  // len8_dlc: a raw DLC 9..F on an 8-byte classic frame
      if (frame.length != 8) return c.fail(problem, "raw DLC suffix '_' only follows 8 data bytes");
      c.advance();
      const int dlc = hex_value(c.peek());
      if (dlc < 9) return c.fail(problem, "raw DLC must be 9..F");
      c.advance();
    }
  }
  if (!c.done() && !is_space(c.peek()))
    return c.fail(problem, "unexpected character after the frame");
  c.skip_spaces();
  if (c.peek() == 'T' || c.peek() == 'R') {  // candump -x direction
    c.advance();
    c.skip_spaces();
  }
  if (!c.done()) return c.fail(problem, "unexpected text after the frame");
  return LineKind::frame;
}

CandumpLog parse_candump_text(std::string_view text, const std::string& source_name,
                              std::string_view interface) {
  CandumpLog log;
  std::uint32_t line_number = 0;
  std::size_t start = 0;
  std::int64_t previous_ns = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++line_number;
    LogRecord record;
    ParseProblem problem;
    const LineKind kind = parse_candump_line(line, record, problem);
    if (kind == LineKind::skip) continue;
    if (kind == LineKind::error) {
      std::ostringstream message;
      message << source_name << ':' << line_number << ':' << problem.column << ": "
              << problem.message;
      throw std::runtime_error(message.str());
    }
    if (!interface.empty() && record.interface != interface) continue;
    if (!log.frames.empty() && record.time_ns < previous_ns) {
      std::ostringstream message;
      message << source_name << ':' << line_number << ":2: timestamp goes backwards";
      throw std::runtime_error(message.str());
    }
    previous_ns = record.time_ns;
    bool known = false;
    for (const auto& name : log.interfaces) known = known || name == record.interface;
    if (!known) log.interfaces.emplace_back(record.interface);
    log.frames.push_back({record.time_ns, line_number, record.frame});
  }
  return log;
}

CandumpLog read_candump_file(const std::string& path, std::string_view interface) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open candump log");
  std::ostringstream content;
  content << in.rdbuf();
  return parse_candump_text(content.str(), path, interface);
}

}  // namespace leakmon::io::canlog
