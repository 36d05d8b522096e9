// Records a sampling group's raw samples to rotating capture files (FORMATS.md), so that what
// the daemon saw can be replayed exactly (`leakmon replay`, the replay driver). Runs on the
// worker thread. Files are `<directory>/<group>-<UTC start>.csv`; a new file starts after
// `rotate_seconds` of source time; the oldest files beyond `keep_files` are deleted.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "capture/capture.hpp"
#include "pipeline/config.hpp"
#include "realtime/sample.hpp"

namespace leakmon::pipeline {

class CaptureRecorder {
 public:
  // `channels`: the column names, in Sample order.
  CaptureRecorder(std::string group, std::vector<std::string> channels, double sample_rate_hz,
                  const RecordingConfig& config);
  ~CaptureRecorder();
  CaptureRecorder(const CaptureRecorder&) = delete;
  CaptureRecorder& operator=(const CaptureRecorder&) = delete;

  void record(const realtime::Sample& sample);
  // Flushes when `flush_seconds` have passed since the last flush (monotonic ns).
  void maybe_flush(std::int64_t now_ns);
  void flush();
  void close();

  std::uint64_t rows_written() const { return rows_; }
  std::vector<std::string> files() const { return files_; }

 private:
  void open(double t);
  void prune();

  std::string group_;
  std::vector<std::string> columns_;
  double sample_rate_hz_;
  RecordingConfig config_;
  std::unique_ptr<capture::CaptureWriter> writer_;
  double file_start_t_ = 0.0;
  std::int64_t last_flush_ns_ = 0;
  std::vector<double> row_;
  std::vector<std::string> files_;  // this run's files, oldest first
  std::uint64_t rows_ = 0;
};

}  // namespace leakmon::pipeline
