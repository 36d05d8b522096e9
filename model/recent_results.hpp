// The last few results of an expensive function of many doubles, looked up by their inputs
// compared bit for bit: a fit that asks again for a point it has evaluated (Levenberg-Marquardt
// re-evaluates its accepted point; the fits before and after an onset share a spool law) gets
// the result it got then. Bit for bit, so that a -0 is not taken for a +0 and no tolerance
// decides which point is meant.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace leakmon::model {

inline bool same_bits(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::bit_cast<std::uint64_t>(a[i]) != std::bit_cast<std::uint64_t>(b[i])) return false;
  }
  return true;
}

// `Key` is anything with data() and size() over doubles (an Eigen vector, a std::array).
template <typename Key, typename Value, std::size_t Kept>
class RecentResults {
 public:
  // The kept result for `key`, or nullptr.
  const Value* find(const Key& key) const {
    for (const auto& entry : entries_) {
      if (same_bits(span(entry.key), span(key))) return &entry.value;
    }
    return nullptr;
  }
  // Keeps a result, dropping the oldest beyond `Kept`.
  void keep(const Key& key, Value value) {
    if (entries_.size() >= Kept) entries_.erase(entries_.begin());
    entries_.push_back({key, std::move(value)});
  }

 private:
  static std::span<const double> span(const Key& key) {
    return {key.data(), static_cast<std::size_t>(key.size())};
  }
  struct Entry {
    Key key;
    Value value;
  };
  std::vector<Entry> entries_;  // newest last
};

}  // namespace leakmon::model
