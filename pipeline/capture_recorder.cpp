#include "pipeline/capture_recorder.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

namespace leakmon::pipeline {

namespace fs = std::filesystem;

CaptureRecorder::CaptureRecorder(std::string group, std::vector<std::string> channels,
                                 double sample_rate_hz, const RecordingConfig& config)
    : group_(std::move(group)), sample_rate_hz_(sample_rate_hz), config_(config) {
  columns_.push_back("t");
  columns_.insert(columns_.end(), channels.begin(), channels.end());
  row_.resize(columns_.size());
  fs::create_directories(config_.directory);
}

CaptureRecorder::~CaptureRecorder() { close(); }

void CaptureRecorder::open(double t) {
  if (writer_) writer_->close();
  const auto now = std::chrono::system_clock::now();
  const auto stamp =
      fmt::format("{:%Y%m%dT%H%M%S}", fmt::gmtime(std::chrono::system_clock::to_time_t(now)));
  std::string path =
      (fs::path(config_.directory) / fmt::format("{}-{}.csv", group_, stamp)).string();
  for (int n = 1; fs::exists(path); ++n) {
    path = (fs::path(config_.directory) / fmt::format("{}-{}-{}.csv", group_, stamp, n)).string();
  }
  capture::Metadata metadata{
      {"sample_rate_hz", fmt::format("{}", sample_rate_hz_)},
      {"source", fmt::format("leakmon recording, sampling group {}", group_)}};
  writer_ = std::make_unique<capture::CaptureWriter>(path, columns_, metadata);
  file_start_t_ = t;
  files_.push_back(path);
  prune();
}

void CaptureRecorder::prune() {
  if (config_.keep_files == 0) return;
  while (files_.size() > config_.keep_files) {
    std::error_code ignored;
    fs::remove(files_.front(), ignored);
    files_.erase(files_.begin());
  }
}

void CaptureRecorder::record(const realtime::Sample& sample) {
  if (!writer_ || sample.t - file_start_t_ >= config_.rotate_seconds) open(sample.t);
  row_[0] = sample.t;
  for (std::size_t i = 1; i < row_.size(); ++i) row_[i] = sample.values[i - 1];
  writer_->write_row(row_);
  ++rows_;
}

void CaptureRecorder::maybe_flush(std::int64_t now_ns) {
  if (now_ns - last_flush_ns_ < static_cast<std::int64_t>(config_.flush_seconds * 1e9)) return;
  last_flush_ns_ = now_ns;
  flush();
}

void CaptureRecorder::flush() {
  if (writer_) writer_->flush();
}

void CaptureRecorder::close() {
  if (writer_) {
    writer_->close();
    writer_.reset();
  }
}

}  // namespace leakmon::pipeline
