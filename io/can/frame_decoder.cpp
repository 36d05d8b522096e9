#include "io/can/frame_decoder.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace leakmon::io::can {

FrameDecoder::FrameDecoder(std::vector<SignalDef> signals)
    : signals_(std::move(signals)),
      value_(signals_.size(), std::numeric_limits<double>::quiet_NaN()),
      received_ns_(signals_.size(), 0),
      has_value_(signals_.size(), 0) {
  for (const auto& s : signals_) {
    if (auto problem = layout_problem(s.layout); !problem.empty()) {
      throw std::invalid_argument("signal '" + s.channel + "': " + problem);
    }
  }
  order_.resize(signals_.size());
  std::iota(order_.begin(), order_.end(), 0U);
  auto key = [this](std::uint32_t i) {
    return key_of(signals_[i].layout.id, signals_[i].layout.extended);
  };
  std::stable_sort(order_.begin(), order_.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
  for (std::uint32_t pos = 0; pos < order_.size(); ++pos) {
    if (ranges_.empty() || ranges_.back().key != key(order_[pos])) {
      ranges_.push_back({key(order_[pos]), pos, 0});
    }
    ++ranges_.back().count;
  }
}

std::size_t FrameDecoder::apply(const CanFrame& frame, std::int64_t received_ns) noexcept {
  if (frame.error || frame.remote) return 0;
  const std::uint64_t key = key_of(frame.id, frame.extended);
  const auto range = std::lower_bound(ranges_.begin(), ranges_.end(), key,
                                      [](const IdRange& r, std::uint64_t k) { return r.key < k; });
  if (range == ranges_.end() || range->key != key) return 0;
  std::size_t updated = 0;
  bool short_frame = false;
  for (std::uint32_t pos = range->first; pos < range->first + range->count; ++pos) {
    const std::uint32_t i = order_[pos];
    double value = 0.0;
    if (!decode(signals_[i].layout, frame, value)) {
      short_frame = true;
      continue;
    }
    value_[i] = value;
    received_ns_[i] = received_ns;
    has_value_[i] = 1;
    ++updated;
  }
  if (short_frame) ++short_frames_;
  if (updated > 0) ++decoded_frames_;
  return updated;
}

std::size_t FrameDecoder::sample(std::span<double> values, std::int64_t now_ns) const noexcept {
  std::size_t stale = 0;
  const std::size_t n = std::min(values.size(), signals_.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!has_value_[i]) {
      values[i] = std::numeric_limits<double>::quiet_NaN();
    } else if (now_ns - received_ns_[i] > signals_[i].max_age_ns) {
      values[i] = std::numeric_limits<double>::quiet_NaN();
      ++stale;
    } else {
      values[i] = value_[i];
    }
  }
  return stale;
}

void FrameDecoder::clear() noexcept {
  std::fill(has_value_.begin(), has_value_.end(), 0);
  std::fill(value_.begin(), value_.end(), std::numeric_limits<double>::quiet_NaN());
}

}  // namespace leakmon::io::can
