// A ring of the newest `capacity` records, sized once at construction: push() overwrites the
// oldest when full and never allocates, so it can live on the worker's real-time path.
//
// stored() is the records in the order of their slots, which is not their age: a sum over it
// sees the same records in the same order every time, so results are reproducible to the bit
// (the detectors' state keeps the slots' order for that reason, see save_ring() below).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "detect/detector_state.hpp"

namespace leakmon::detect {

template <class T>
class Ring {
 public:
  explicit Ring(std::size_t capacity = 0) : slots_(capacity) {}

  std::size_t capacity() const { return slots_.size(); }
  std::size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  bool full() const { return count_ == slots_.size(); }

  // Adds the newest record (the oldest is dropped when full). A ring of capacity 0 keeps nothing.
  void push(const T& record) {
    if (slots_.empty()) return;
    slots_[next_] = record;
    next_ = (next_ + 1) % slots_.size();
    if (count_ < slots_.size()) ++count_;
  }
  void clear() { next_ = count_ = 0; }

  // age 0: the newest; age < size().
  const T& newest(std::size_t age = 0) const {
    return slots_[(next_ + slots_.size() - 1 - age) % slots_.size()];
  }
  T& newest(std::size_t age = 0) {
    return slots_[(next_ + slots_.size() - 1 - age) % slots_.size()];
  }
  // i 0: the oldest; i < size().
  const T& oldest(std::size_t i = 0) const {
    return slots_[(next_ + slots_.size() - count_ + i) % slots_.size()];
  }
  // Every record, in slot order (see the file comment).
  std::span<const T> stored() const { return {slots_.data(), count_}; }
  // The slot the next push() writes.
  std::size_t next_slot() const { return next_; }

  // The records back in their slots: `in_slot_order` as stored() gave them, `next` as
  // next_slot() did. Throws StateError when they do not fit this ring.
  void restore(std::span<const T> in_slot_order, std::size_t next) {
    const std::size_t n = in_slot_order.size();
    // Until the ring is full its records fill the slots from the first, so next == size().
    const bool fits =
        n < slots_.size() ? next == n : n == slots_.size() && next < std::max<std::size_t>(n, 1);
    if (!fits) {
      throw StateError("a ring of " + std::to_string(slots_.size()) + " records does not take " +
                       std::to_string(n) + " records with the next slot at " +
                       std::to_string(next));
    }
    std::copy(in_slot_order.begin(), in_slot_order.end(), slots_.begin());
    count_ = n;
    next_ = next;
  }

 private:
  std::vector<T> slots_;
  std::size_t next_ = 0, count_ = 0;
};

// A ring's records under `prefix`: one list per field (RecordField) in slot order, and
// `prefix.next`, so that a restored ring sums in the same order as the one saved; and
// `prefix.capacity`: a ring of another length (other options) does not take it.
template <class T, std::size_t N>
void save_ring(DetectorState& state, std::string_view prefix, const Ring<T>& ring,
               const std::array<RecordField<T>, N>& fields) {
  put_records(state, prefix, ring.stored(), fields);
  state.put_count(state_key(prefix, "next"), ring.next_slot());
  state.put_count(state_key(prefix, "capacity"), ring.capacity());
}

template <class T, std::size_t N>
void restore_ring(const DetectorState& state, std::string_view prefix, Ring<T>& ring,
                  const std::array<RecordField<T>, N>& fields) {
  const std::size_t capacity = state.get_count(state_key(prefix, "capacity"));
  if (capacity != ring.capacity()) {
    throw StateError("'" + std::string(prefix) + "' was a ring of " + std::to_string(capacity) +
                     " records, this configuration's holds " + std::to_string(ring.capacity()));
  }
  const std::size_t n = record_count(state, prefix, fields);
  std::vector<T> records(n);
  get_records(state, prefix, fields, std::span<T>(records));
  ring.restore(records, state.get_count(state_key(prefix, "next")));
}

}  // namespace leakmon::detect
