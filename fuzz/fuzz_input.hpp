// The harnesses' view of libFuzzer's byte string: takes values from the front, zeros once it
// runs out, so every input is a complete (if dull) test case. Multi-byte reads fetch their
// bytes in sequence statements: inside one expression the evaluation order of two `byte()`
// calls would be unspecified and the same input could decode differently per compiler.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace leakmon::fuzz {

class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  std::size_t remaining() const { return size_; }

  std::uint8_t byte() {
    if (size_ == 0) return 0;
    --size_;
    return *data_++;
  }
  std::uint16_t u16_little_endian() {
    const unsigned low = byte();
    const unsigned high = byte();
    return static_cast<std::uint16_t>(low | high << 8);
  }
  std::uint16_t u16_big_endian() {
    const unsigned high = byte();
    const unsigned low = byte();
    return static_cast<std::uint16_t>(high << 8 | low);
  }
  // Copies up to `n` bytes into `out`; returns how many there were.
  std::size_t take(void* out, std::size_t n) {
    const std::size_t count = std::min(n, size_);
    std::memcpy(out, data_, count);
    data_ += count;
    size_ -= count;
    return count;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

}  // namespace leakmon::fuzz
