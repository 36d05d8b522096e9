#include "capture/capture.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <cmath>

namespace leakmon::capture {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

}  // namespace

PhysicalRange physical_range(std::string_view column) {
  if (column == "p1" || column == "p2" || column == "ps" || column == "pt") return {-1e6, 100e6};
  if (column == "x" || column == "xref") return {-10.0, 10.0};
  if (column == "u") return {-1000.0, 1000.0};
  if (column == "temp") return {-100.0, 500.0};
  return {-1e12, 1e12};
}

std::string excerpt(std::string_view text, std::size_t max_chars) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (i == max_chars) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02x}", c);
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

CaptureReader::CaptureReader(const std::string& path) : path_(path), in_(path) {
  if (!in_) throw CaptureError(fmt::format("{}: cannot open file", path));
  while (std::getline(in_, line_)) {
    ++line_number_;
    std::string_view text = trim(line_);
    if (line_number_ == 1 && text.starts_with("\xef\xbb\xbf")) text.remove_prefix(3);
    if (text.empty()) continue;
    if (text.front() == '#') {
      text.remove_prefix(1);
      auto colon = text.find(':');
      if (colon != std::string_view::npos) {
        auto key = trim(text.substr(0, colon));
        auto value = trim(text.substr(colon + 1));
        if (!key.empty() && key.find(' ') == std::string_view::npos) {
          metadata_.emplace_back(std::string(key), std::string(value));
        }
      }
      continue;
    }
    std::size_t start = 0;
    while (true) {
      auto comma = text.find(',', start);
      auto name =
          trim(text.substr(start, comma == std::string_view::npos ? text.npos : comma - start));
      if (name.empty()) fail(columns_.size() + 1, "empty column name in header");
      if (std::find(columns_.begin(), columns_.end(), name) != columns_.end()) {
        fail(columns_.size() + 1, fmt::format("duplicate column '{}' in header", excerpt(name)));
      }
      columns_.emplace_back(name);
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    auto t = std::find(columns_.begin(), columns_.end(), "t");
    if (t == columns_.end()) {
      fail(1, fmt::format("header has no 't' column (header: '{}')", excerpt(text)));
    }
    t_index_ = static_cast<std::size_t>(t - columns_.begin());
    for (const auto& name : columns_) ranges_.push_back(physical_range(name));
    return;
  }
  throw CaptureError(
      fmt::format("{}:{}: no header line (expected e.g. 't,p1,p2')", path, line_number_ + 1));
}

void CaptureReader::fail(std::size_t column, std::string_view message) const {
  throw CaptureError(fmt::format("{}:{}:{}: {}", path_, line_number_, column, message));
}

std::optional<std::string> CaptureReader::metadata_value(std::string_view key) const {
  for (const auto& [k, v] : metadata_) {
    if (k == key) return v;
  }
  return std::nullopt;
}

std::optional<std::size_t> CaptureReader::column_index(std::string_view name) const {
  auto it = std::find(columns_.begin(), columns_.end(), name);
  if (it == columns_.end()) return std::nullopt;
  return static_cast<std::size_t>(it - columns_.begin());
}

bool CaptureReader::next(std::span<double> row) {
  while (std::getline(in_, line_)) {
    ++line_number_;
    std::string_view text = trim(line_);
    if (text.empty() || text.front() == '#') continue;
    std::size_t column = 0;
    std::size_t start = 0;
    while (true) {
      auto comma = text.find(',', start);
      auto field =
          trim(text.substr(start, comma == std::string_view::npos ? text.npos : comma - start));
      if (column >= columns_.size()) {
        fail(column + 1,
             fmt::format("too many fields: the header has {} columns", columns_.size()));
      }
      double value = kGap;
      if (!field.empty() && !iequals(field, "nan")) {
        const char* first = field.data();
        const char* last = field.data() + field.size();
        if (*first == '+') ++first;
        auto [ptr, ec] = std::from_chars(first, last, value);
        if (ec == std::errc::result_out_of_range && ptr == last) {
          value = HUGE_VAL;  // 1e999: beyond double, certainly beyond any transducer
        } else if (ec != std::errc() || ptr != last) {
          fail(column + 1, fmt::format("column '{}': '{}' is not a number",
                                       excerpt(columns_[column]), excerpt(field)));
        }
        if (column != t_index_ && !(value >= ranges_[column].lo && value <= ranges_[column].hi)) {
          if (rejected_++ == 0) {
            first_rejected_ = fmt::format("line {}, column '{}': '{}'", line_number_,
                                          excerpt(columns_[column]), excerpt(field, 30));
          }
          value = kGap;
        }
        if (column == t_index_ && !std::isfinite(value)) {
          fail(column + 1, fmt::format("column 't': '{}' is not a finite time", excerpt(field)));
        }
      }
      row[column] = value;
      ++column;
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    if (column != columns_.size()) {
      fail(column,
           fmt::format("too few fields: {} of the header's {} columns", column, columns_.size()));
    }
    double t = row[t_index_];
    if (std::isnan(t)) fail(t_index_ + 1, "column 't' is empty: every row needs a time");
    if (have_t_ && !(t > last_t_)) {
      fail(t_index_ + 1,
           fmt::format("column 't': {} does not increase (previous row {})", t, last_t_));
    }
    last_t_ = t;
    have_t_ = true;
    return true;
  }
  if (!have_t_) {
    throw CaptureError(fmt::format("{}: no samples (a header but not a single row)", path_));
  }
  if (rejected_ > 0 && !warned_) {
    warned_ = true;
    spdlog::warn(
        "{}: {} value(s) not finite or beyond the transducer's physical range were read as gaps "
        "(first: {})",
        path_, rejected_, first_rejected_);
  }
  return false;
}

bool Capture::has(std::string_view name) const {
  return std::find(columns.begin(), columns.end(), name) != columns.end();
}

const std::vector<double>& Capture::column(std::string_view name) const {
  auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) {
    throw CaptureError(fmt::format("{}: capture has no column '{}'", path, name));
  }
  return values[static_cast<std::size_t>(it - columns.begin())];
}

std::vector<double>& Capture::column(std::string_view name) {
  return const_cast<std::vector<double>&>(static_cast<const Capture&>(*this).column(name));
}

std::optional<std::string> Capture::metadata_value(std::string_view key) const {
  for (const auto& [k, v] : metadata) {
    if (k == key) return v;
  }
  return std::nullopt;
}

double Capture::sample_rate_hz() const {
  if (auto rate = metadata_value("sample_rate_hz")) {
    double value = 0;
    auto [ptr, ec] = std::from_chars(rate->data(), rate->data() + rate->size(), value);
    if (ec == std::errc() && ptr == rate->data() + rate->size() && value > 0) return value;
    throw CaptureError(fmt::format("{}: metadata sample_rate_hz '{}' is not a positive number",
                                   path, excerpt(*rate)));
  }
  const auto& t = column("t");
  if (t.size() < 2)
    throw CaptureError(fmt::format("{}: too few rows to know the sample rate", path));
  std::vector<double> dt(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) dt[i - 1] = t[i] - t[i - 1];
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  return 1.0 / dt[dt.size() / 2];
}

Capture read_capture(const std::string& path) {
  CaptureReader reader(path);
  Capture capture;
  capture.path = path;
  capture.metadata = reader.metadata();
  capture.columns = reader.columns();
  capture.values.resize(capture.columns.size());
  std::vector<double> row(capture.columns.size());
  while (reader.next(row)) {
    for (std::size_t c = 0; c < row.size(); ++c) capture.values[c].push_back(row[c]);
  }
  return capture;
}

void append_number(std::string& out, double value) {
  if (std::isnan(value)) return;
  char buf[32];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);
  (void)ec;
  out.append(buf, ptr);
}

CaptureWriter::CaptureWriter(const std::string& path, std::vector<std::string> columns,
                             const Metadata& metadata)
    : path_(path), columns_(std::move(columns)), out_(path, std::ios::trunc) {
  if (!out_) throw CaptureError(fmt::format("{}: cannot open for writing", path));
  if (std::find(columns_.begin(), columns_.end(), "t") == columns_.end()) {
    throw CaptureError(fmt::format("{}: a capture needs a 't' column", path));
  }
  buffer_ = "# leakmon capture v1\n";
  for (const auto& [key, value] : metadata) buffer_ += fmt::format("# {}: {}\n", key, value);
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (i) buffer_ += ',';
    buffer_ += columns_[i];
  }
  buffer_ += '\n';
  flush();
}

CaptureWriter::~CaptureWriter() {
  try {
    close();
  } catch (...) {
  }
}

void CaptureWriter::write_row(std::span<const double> row) {
  for (std::size_t i = 0; i < row.size(); ++i) {
    if (i) buffer_ += ',';
    append_number(buffer_, row[i]);
  }
  buffer_ += '\n';
  ++rows_;
  if (buffer_.size() > (1u << 16)) flush();
}

void CaptureWriter::flush() {
  if (!out_.is_open()) return;
  out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  out_.flush();
  buffer_.clear();
  if (!out_) throw CaptureError(fmt::format("{}: write failed", path_));
}

void CaptureWriter::close() {
  if (!out_.is_open()) return;
  flush();
  out_.close();
}

void write_capture(const std::string& path, const Capture& capture) {
  CaptureWriter writer(path, capture.columns, capture.metadata);
  std::vector<double> row(capture.columns.size());
  for (std::size_t r = 0; r < capture.rows(); ++r) {
    for (std::size_t c = 0; c < row.size(); ++c) row[c] = capture.values[c][r];
    writer.write_row(row);
  }
  writer.close();
}

}  // namespace leakmon::capture
