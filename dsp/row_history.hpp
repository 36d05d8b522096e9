// A sliding history of multi-channel rows indexed by absolute position (sample number, or
// coefficient number at a DWT level). Rows are stored channel-interleaved and contiguous, so a
// span of rows is one block of memory that a loop over channels vectorises. The storage is sized
// once; when it fills, the rows still needed move to the front (a memmove every few windows),
// so appending never allocates.
#pragma once

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace leakmon::dsp {

class RowHistory {
 public:
  RowHistory() = default;
  RowHistory(std::size_t capacity_rows, std::size_t channels)
      : data_(capacity_rows * channels), channels_(channels), capacity_(capacity_rows) {}

  // Empties the history; the next appended row gets absolute index `next`.
  void restart(std::uint64_t next) noexcept { base_ = keep_from_ = end_ = next; }
  std::uint64_t end() const noexcept { return end_; }
  bool empty() const noexcept { return end_ == keep_from_; }

  // Rows before `index` will not be read again.
  void release_before(std::uint64_t index) noexcept {
    if (index > keep_from_) keep_from_ = index < end_ ? index : end_;
  }

  // Appends `count` rows (contiguous) and returns the first.
  double* append(std::size_t count = 1) noexcept {
    if (end_ - base_ + count > capacity_) compact();
    assert(end_ - base_ + count <= capacity_);
    double* row = data_.data() + (end_ - base_) * channels_;
    end_ += count;
    return row;
  }

  const double* row(std::uint64_t index) const noexcept {
    assert(index >= keep_from_ && index < end_);
    return data_.data() + (index - base_) * channels_;
  }

 private:
  void compact() noexcept {
    const std::size_t kept = end_ - keep_from_;
    std::memmove(data_.data(), data_.data() + (keep_from_ - base_) * channels_,
                 kept * channels_ * sizeof(double));
    base_ = keep_from_;
  }

  std::vector<double> data_;
  std::size_t channels_ = 0;
  std::size_t capacity_ = 0;
  std::uint64_t base_ = 0;       // absolute index of data_'s first row
  std::uint64_t keep_from_ = 0;  // first row still needed
  std::uint64_t end_ = 0;        // one past the newest row
};

}  // namespace leakmon::dsp
