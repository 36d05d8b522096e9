// Single-producer single-consumer lock-free ring buffer between the acquisition loop (producer,
// real-time) and the worker (consumer), after rigtorp/SPSCQueue.
//
// Design, and why:
// - Fixed capacity, storage allocated once in the constructor: the producer never allocates.
// - try_push() never waits: when the ring is full it returns false and the loop counts a drop;
//   a real-time thread must not be held up by a slow consumer.
// - One slot is left empty so that head == tail means empty and head + 1 == tail means full
//   without a shared counter.
// - write_index_ is written only by the producer and read_index_ only by the consumer. Each
//   lives on its own cache line (alignas(kCacheLine)) so the two cores do not bounce one line
//   between them for every element ("false sharing").
// - Each side keeps a cached copy of the other side's index (on its own line) and reloads the
//   shared index only when the cache says the ring looks full (producer) or empty (consumer).
//   Under steady flow this removes most cross-core traffic.
//
// Memory order:
// - Producer: writes the slot, then write_index_.store(next, release). The release makes the
//   slot's contents visible to any thread that acquires that index value.
// - Consumer: write_index_.load(acquire) before reading the slot, pairing with the release
//   above, so it never reads a half-written slot.
// - Consumer: reads the slot, then read_index_.store(next, release); the producer's
//   read_index_.load(acquire) pairs with it, so the producer never overwrites a slot the
//   consumer is still reading.
// - Each side reads its own index with relaxed order: only it ever writes it.
//
// As in rigtorp's SPSCQueue, a result that says whether anything happened is [[nodiscard]]
// (a dropped push must be counted), misuse (pop() on an empty ring) is asserted in debug
// builds, and the cache-line layout is checked at compile time.
#pragma once

#include <atomic>
#include <cassert>
#include <cstddef>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>

namespace leakmon::realtime {

inline constexpr std::size_t kCacheLine = 64;

template <typename T>
class SpscRing {
  static_assert(std::is_nothrow_copy_assignable_v<T>, "slots are overwritten in place");
  static_assert(std::is_default_constructible_v<T>, "slots are constructed up front");

 public:
  explicit SpscRing(std::size_t capacity)
      : slots_count_(checked_slots(capacity)), slots_(std::make_unique<T[]>(slots_count_)) {
    // The four indices each start their own cache line, after the line of slots_count_ and
    // slots_, so the object spans at least five lines and is itself line-aligned.
    static_assert(alignof(SpscRing) == kCacheLine);
    static_assert(sizeof(SpscRing) >= 5 * kCacheLine);
    static_assert(std::atomic<std::size_t>::is_always_lock_free);
  }
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  [[nodiscard]] std::size_t capacity() const noexcept { return slots_count_ - 1; }

  // Producer only. False when full (nothing written).
  [[nodiscard]] bool try_push(const T& value) noexcept {
    const std::size_t write = write_index_.load(std::memory_order_relaxed);
    std::size_t next = write + 1;
    if (next == slots_count_) next = 0;
    if (next == cached_read_index_) {
      cached_read_index_ = read_index_.load(std::memory_order_acquire);
      if (next == cached_read_index_) return false;
    }
    slots_[write] = value;
    write_index_.store(next, std::memory_order_release);
    return true;
  }

  // Consumer only. The oldest element, or nullptr when empty; valid until pop().
  [[nodiscard]] T* front() noexcept {
    const std::size_t read = read_index_.load(std::memory_order_relaxed);
    if (read == cached_write_index_) {
      cached_write_index_ = write_index_.load(std::memory_order_acquire);
      if (read == cached_write_index_) return nullptr;
    }
    return &slots_[read];
  }

  // Consumer only, after front() returned an element.
  void pop() noexcept {
    const std::size_t read = read_index_.load(std::memory_order_relaxed);
    assert(read != write_index_.load(std::memory_order_acquire) &&
           "SpscRing::pop() only after front() returned an element");
    std::size_t next = read + 1;
    if (next == slots_count_) next = 0;
    read_index_.store(next, std::memory_order_release);
  }

  // Consumer only: copy out and pop the oldest element. False when empty.
  [[nodiscard]] bool try_pop(T& out) noexcept {
    T* element = front();
    if (element == nullptr) return false;
    out = *element;
    pop();
    return true;
  }

  // Either side, approximate (for metrics): elements currently queued.
  [[nodiscard]] std::size_t size() const noexcept {
    const std::ptrdiff_t diff =
        static_cast<std::ptrdiff_t>(write_index_.load(std::memory_order_acquire)) -
        static_cast<std::ptrdiff_t>(read_index_.load(std::memory_order_acquire));
    const auto queued = static_cast<std::size_t>(
        diff < 0 ? diff + static_cast<std::ptrdiff_t>(slots_count_) : diff);
    assert(queued <= capacity());
    return queued;
  }
  [[nodiscard]] bool empty() const noexcept { return size() == 0; }

 private:
  // One slot more than the capacity; the index arithmetic (and the slot array) must fit.
  static std::size_t checked_slots(std::size_t capacity) {
    if (capacity < 1) throw std::invalid_argument("SpscRing capacity must be at least 1");
    if (capacity > std::numeric_limits<std::ptrdiff_t>::max() / sizeof(T) - 1) {
      throw std::invalid_argument("SpscRing capacity too large");
    }
    return capacity + 1;
  }

  const std::size_t slots_count_;
  const std::unique_ptr<T[]> slots_;

  alignas(kCacheLine) std::atomic<std::size_t> write_index_{0};
  alignas(kCacheLine) std::size_t cached_read_index_ = 0;  // producer's copy of read_index_
  alignas(kCacheLine) std::atomic<std::size_t> read_index_{0};
  // alignas also pads the object's end, so whatever follows it is off the consumer's line.
  alignas(kCacheLine) std::size_t cached_write_index_ = 0;  // consumer's copy of write_index_
};

}  // namespace leakmon::realtime
