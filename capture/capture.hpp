// The capture CSV format of FORMATS.md: `#` comment lines (`# key: value` carries metadata),
// one header line naming the columns (`t` required, others optional, any order), then one row
// per sample. An empty field or `nan` is a gap. Errors name file, line and column and quote at
// most a short excerpt of the offending text. A UTF-8 byte-order mark (as spreadsheet tools
// write) is skipped. A value that is not finite (`inf`) or beyond what the channel's transducer
// can physically report (physical_range()) becomes a gap; the reader counts them and logs one
// warning per file at its end. A capture without a single row is an error ("no samples") for
// every reader, so that every command treats it alike.
#pragma once

#include <cstdint>
#include <fstream>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace leakmon::capture {

class CaptureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr double kGap = std::numeric_limits<double>::quiet_NaN();

// The values a column can physically hold, generously (MODEL.md units: Pa, m, V, degC): beyond
// them a value is a decoding or unit error, not a measurement. Pressures (p1, p2, ps, pt)
// [-1, 100] MPa, positions (x, xref) +-10 m, the valve command u +-1000, temperatures
// [-100, 500] degC; any other column +-1e12.
struct PhysicalRange {
  double lo, hi;
};
PhysicalRange physical_range(std::string_view column);

// At most `max_chars` of `text` for an error message, "..." marking a cut; control characters
// escaped.
std::string excerpt(std::string_view text, std::size_t max_chars = 60);

using Metadata = std::vector<std::pair<std::string, std::string>>;

// Reads a capture row by row, so that captures larger than memory can be streamed.
class CaptureReader {
 public:
  explicit CaptureReader(const std::string& path);

  const std::string& path() const { return path_; }
  const std::vector<std::string>& columns() const { return columns_; }
  const Metadata& metadata() const { return metadata_; }
  std::optional<std::string> metadata_value(std::string_view key) const;
  // Index of a column in columns(), or nullopt when the capture has no such column.
  std::optional<std::size_t> column_index(std::string_view name) const;
  std::size_t t_index() const { return t_index_; }
  // Line number (1-based) of the row last returned by next().
  std::size_t line_number() const { return line_number_; }

  // Reads the next row into `row` (size columns().size()). Returns false at end of file.
  // Throws CaptureError naming file, line and column on malformed input or non-increasing t,
  // and at the end of a file that had no row at all.
  bool next(std::span<double> row);

  // Values that became gaps for being non-finite or beyond physical_range(), so far.
  std::uint64_t rejected_values() const { return rejected_; }

 private:
  [[noreturn]] void fail(std::size_t column, std::string_view message) const;

  std::string path_;
  std::ifstream in_;
  std::vector<std::string> columns_;
  Metadata metadata_;
  std::size_t t_index_ = 0;
  std::size_t line_number_ = 0;
  std::string line_;
  double last_t_ = -std::numeric_limits<double>::infinity();
  bool have_t_ = false;
  std::vector<PhysicalRange> ranges_;  // per column
  std::uint64_t rejected_ = 0;
  std::string first_rejected_;  // where and what, for the warning
  bool warned_ = false;
};

// A whole capture in memory, column by column.
struct Capture {
  std::string path;
  Metadata metadata;
  std::vector<std::string> columns;         // header order, includes "t"
  std::vector<std::vector<double>> values;  // values[c][row]

  std::size_t rows() const { return values.empty() ? 0 : values.front().size(); }
  bool has(std::string_view name) const;
  // The column's samples; throws CaptureError naming the file when the column is missing.
  const std::vector<double>& column(std::string_view name) const;
  std::vector<double>& column(std::string_view name);
  std::optional<std::string> metadata_value(std::string_view key) const;
  // `# sample_rate_hz:` when present, else estimated from the median spacing of t.
  double sample_rate_hz() const;
};

Capture read_capture(const std::string& path);

// Writes the capture format. Values are printed in the shortest form that reads back to the
// same double, so record -> replay is exact; NaN is written as an empty field.
class CaptureWriter {
 public:
  CaptureWriter(const std::string& path, std::vector<std::string> columns,
                const Metadata& metadata);
  ~CaptureWriter();
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;

  const std::string& path() const { return path_; }
  const std::vector<std::string>& columns() const { return columns_; }
  void write_row(std::span<const double> row);
  void flush();
  void close();
  std::uint64_t rows_written() const { return rows_; }

 private:
  std::string path_;
  std::vector<std::string> columns_;
  std::ofstream out_;
  std::string buffer_;
  std::uint64_t rows_ = 0;
};

void write_capture(const std::string& path, const Capture& capture);

// Appends `value` to `out` in the capture format's number form (shortest round-trip; NaN empty).
void append_number(std::string& out, double value);

}  // namespace leakmon::capture
