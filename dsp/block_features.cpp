#include "dsp/block_features.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "dsp/incremental_plan.hpp"
#include "dsp/interleaved_kernels.hpp"
#include "dsp/row_history.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

namespace {

constexpr std::size_t kLanes = BlockFeatures::kLanes;

// With GCC, `flatten` inlines the kernels into each clone, so that they too run in its
// instruction set (called out of line they are the baseline's: 102 against 131 M samples/s).
// Clang refuses `flatten` on a multiversioned function; there only the function itself is cloned.
#if defined(__clang__)
#define LEAKMON_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define LEAKMON_AVX2_CLONES __attribute__((target_clones("avx2", "default"), flatten))
#endif

// The windows of one batch, lane-interleaved edge buffers ("rows" of kLanes values, value w
// belonging to window w) and the clean coefficients of the single channel. The arithmetic is
// StreamingFeatures' with its channels replaced by consecutive windows: decimate_rows over
// kLanes interleaved lanes, each lane one sum in the batch transform's order.
struct IncrementalBatches {
  IncrementalBatches(const FeatureParams& params, std::vector<LevelPlan> plan)
      : levels(std::move(plan)) {
    const std::size_t taps = levels.front().filter.size();
    for (std::size_t j = 0; j < levels.size(); ++j) {
      const LevelPlan& l = levels[j];
      const std::size_t clean = l.clean_hi - l.clean_lo;
      const std::size_t hop = params.step >> (j + 1);
      coeffs.emplace_back(2 * (clean + kLanes * hop + taps), 1);
      left_buf.emplace_back((l.dec.left_ext + l.edge_left) * kLanes);
      right_buf.emplace_back((l.edge_right + l.dec.right_ext) * kLanes);
      left_out.emplace_back(l.clean_lo * kLanes);
      right_out.emplace_back((l.dec.n_out - l.clean_hi) * kLanes);
    }
    for (std::size_t j = 0; j < levels.size(); ++j) {
      const LevelPlan& l = levels[j];
      append_extension_slots(l, params.mode, left_buf[j].data() + l.dec.left_ext * kLanes,
                             right_buf[j].data(), kLanes, extension);
      extension_end.push_back(extension.size());
    }
  }

  void restart() noexcept {
    for (auto& h : coeffs) h.restart(0);
  }

  // Energies of the windows starting at starts[0..kLanes) (ascending, each a multiple of
  // 2^level, all within `samples`).
  // Built for AVX2 as well as the baseline (chosen at load time): 8 lanes are 2 AVX registers
  // instead of 4 SSE2 ones. AVX2 brings no FMA, so nothing is contracted: same rounding.
  LEAKMON_AVX2_CLONES void compute(const RowHistory& samples,
                                   const std::array<std::uint64_t, kLanes>& starts,
                                   std::array<double, kLanes>& energy) noexcept {
    for (std::size_t j = 0; j < levels.size(); ++j) {
      const LevelPlan& l = levels[j];
      const RowHistory& input = j == 0 ? samples : coeffs[j - 1];
      RowHistory& output = coeffs[j];

      // Clean coefficients of this level that the last window needs and no earlier one had.
      const std::uint64_t first = (starts.front() >> (j + 1)) + l.clean_lo;
      const std::uint64_t last = (starts.back() >> (j + 1)) + l.clean_hi;
      if (output.end() < first || output.empty()) output.restart(first);
      if (last > output.end()) {
        const std::uint64_t from = output.end();
        const std::size_t count = last - from;
        double* out = output.append(count);
        decimate_one_channel_paired(input.row(2 * from + l.dec.phase), count, l.filter, out);
      }

      // The input's edges, window w in lane w: from the boundary outputs of the level below
      // (already lane-interleaved) or from the single-channel clean history (transposed).
      const std::size_t n_in = l.dec.n_in;
      const std::size_t right_first = n_in - l.edge_right;
      double* left_real = left_buf[j].data() + l.dec.left_ext * kLanes;
      double* right_real = right_buf[j].data();
      const std::size_t left_from_below = j == 0 ? 0 : levels[j - 1].clean_lo;
      const std::size_t right_clean_end = j == 0 ? n_in : levels[j - 1].clean_hi;
      if (j > 0) {
        std::memcpy(left_real, left_out[j - 1].data(), left_from_below * kLanes * sizeof(double));
        std::memcpy(right_real + (right_clean_end - right_first) * kLanes, right_out[j - 1].data(),
                    (n_in - right_clean_end) * kLanes * sizeof(double));
      }
      transpose(input, starts, j, left_from_below, l.edge_left,
                left_real + left_from_below * kLanes);
      transpose(input, starts, j, right_first, right_clean_end, right_real);
      for (std::size_t e = j == 0 ? 0 : extension_end[j - 1]; e < extension_end[j]; ++e) {
        extension[e].fill(kLanes);
      }

      decimate_rows(left_buf[j].data() + (l.dec.left_ext + l.dec.phase) * kLanes, l.clean_lo,
                    kLanes, l.filter, left_out[j].data());
      decimate_rows_right_end(right_real + (2 * l.clean_hi + l.dec.phase - right_first) * kLanes,
                              l.dec.n_out - l.clean_hi, kLanes, l.filter, l.dec, l.clean_hi,
                              right_out[j].data());
    }

    const LevelPlan& top = levels.back();
    energy.fill(0.0);
    add_squares(left_out.back().data(), top.clean_lo, kLanes, energy.data());
    for (std::size_t w = 0; w < kLanes; ++w) {
      const std::uint64_t origin = starts[w] >> levels.size();
      add_squares(coeffs.back().row(origin + top.clean_lo), top.clean_hi - top.clean_lo, 1,
                  &energy[w]);
    }
    add_squares(right_out.back().data(), top.dec.n_out - top.clean_hi, kLanes, energy.data());
  }

  // rows[(i - from) * kLanes + w] = input value i (from the window's start) of level j's input
  // for window w, i in [from, to).
  static void transpose(const RowHistory& input, const std::array<std::uint64_t, kLanes>& starts,
                        std::size_t j, std::size_t from, std::size_t to, double* rows) noexcept {
    if (from >= to) return;
    for (std::size_t w = 0; w < kLanes; ++w) {
      const double* a = input.row((starts[w] >> j) + from);
      for (std::size_t i = 0; i < to - from; ++i) rows[i * kLanes + w] = a[i];
    }
  }

  // After the windows before `next_start` are done: drop what no later window reads.
  void release_before(std::uint64_t next_start) noexcept {
    for (std::size_t j = 0; j < levels.size(); ++j) {
      coeffs[j].release_before((next_start >> (j + 1)) + levels[j].clean_lo);
    }
  }

  std::size_t detail_count() const noexcept { return levels.back().dec.n_out; }

  std::vector<LevelPlan> levels;
  std::vector<RowHistory> coeffs;  // per level: the clean coefficients of the one channel
  std::vector<std::vector<double>> left_buf, right_buf, left_out, right_out;
  std::vector<ExtensionSlot> extension;    // all levels' extension values, level by level
  std::vector<std::size_t> extension_end;  // per level: one past its last slot
};

}  // namespace

#undef LEAKMON_AVX2_CLONES

struct BlockFeatures::Engine {
  explicit Engine(const FeatureParams& p) : params(p) {
    validate(params);
    if (auto plan = plan_incremental(params, wavelet(params.wavelet))) {
      batches.emplace(params, std::move(*plan));
      samples = RowHistory(2 * (params.window + kLanes * params.step), 1);
    } else {
      fallback.emplace(params, 1);
    }
    reset();
  }

  void reset() noexcept {
    seen = 0;
    next_start = 0;
    gap_end = 0;
    gaps_checked = 0;
    done_count = 0;
    samples.restart(0);
    if (batches) batches->restart();
    if (fallback) fallback->reset();
  }

  std::size_t consume(std::span<const double> input) noexcept {
    done_count = 0;
    if (fallback) return consume_one_by_one(input);
    std::size_t used = 0;
    if (seen < next_start) {  // step > window: samples in no window
      used = static_cast<std::size_t>(std::min<std::uint64_t>(next_start - seen, input.size()));
      seen += used;
      if (used == input.size()) return used;
    }
    if (samples.end() != seen) samples.restart(seen);
    const std::uint64_t batch_end = next_start + params.window + (kLanes - 1) * params.step;
    const auto take =
        static_cast<std::size_t>(std::min<std::uint64_t>(batch_end - seen, input.size() - used));
    std::memcpy(samples.append(take), input.data() + used, take * sizeof(double));
    seen += take;
    used += take;
    if (seen < next_start + params.window) return used;

    const auto ready =
        static_cast<std::size_t>((seen - next_start - params.window) / params.step + 1);
    std::array<std::uint64_t, kLanes> starts{};
    for (std::size_t w = 0; w < kLanes; ++w) {
      // Lanes beyond the completed windows repeat the last one: their results are not used.
      starts[w] = next_start + std::min(w, ready - 1) * params.step;
    }
    std::array<double, kLanes> energy{};
    batches->compute(samples, starts, energy);
    for (std::size_t w = 0; w < ready; ++w) {
      note_gaps(std::max(gaps_checked, starts[w]), starts[w] + params.window);
      const bool gap = gap_end > starts[w];
      done[w] = {starts[w] + params.window - 1,
                 gap ? DetailFeature{} : feature_from_energy(energy[w], batches->detail_count())};
    }
    done_count = ready;
    next_start += ready * params.step;
    samples.release_before(next_start);
    batches->release_before(next_start);
    return used;
  }

  // gap_end = one past the last NaN among samples [first, end); samples before a window's start
  // cannot invalidate it, so they need no look.
  void note_gaps(std::uint64_t first, std::uint64_t end) noexcept {
    if (first >= end) return;
    const double* x = samples.row(first);
    for (std::uint64_t t = first; t < end; ++t, ++x) {
      if (std::isnan(*x)) gap_end = t + 1;
    }
    gaps_checked = end;
  }

  std::size_t consume_one_by_one(std::span<const double> input) noexcept {
    std::size_t used = 0;
    while (used < input.size() && done_count < kLanes) {
      if (fallback->push(input.subspan(used++, 1))) {
        done[done_count++] = {seen + used - 1, fallback->latest()[0]};
      }
    }
    seen += used;
    return used;
  }

  FeatureParams params;
  std::optional<IncrementalBatches> batches;
  std::optional<StreamingFeatures> fallback;  // steps that change the decimation phase
  RowHistory samples;
  std::uint64_t seen = 0;
  std::uint64_t next_start = 0;    // first sample of the next window to complete
  std::uint64_t gap_end = 0;       // one past the last NaN sample looked at
  std::uint64_t gaps_checked = 0;  // samples before it have been looked at for NaN
  std::array<WindowFeature, kLanes> done{};
  std::size_t done_count = 0;
};

BlockFeatures::BlockFeatures(const FeatureParams& params) : engine_(new Engine(params)) {}
BlockFeatures::~BlockFeatures() { delete engine_; }
BlockFeatures::BlockFeatures(BlockFeatures&& other) noexcept
    : engine_(std::exchange(other.engine_, nullptr)) {}
BlockFeatures& BlockFeatures::operator=(BlockFeatures&& other) noexcept {
  if (this != &other) {
    delete engine_;
    engine_ = std::exchange(other.engine_, nullptr);
  }
  return *this;
}

std::size_t BlockFeatures::consume(std::span<const double> samples) noexcept {
  return engine_->consume(samples);
}
std::span<const WindowFeature> BlockFeatures::completed() const noexcept {
  return std::span<const WindowFeature>(engine_->done).first(engine_->done_count);
}
std::uint64_t BlockFeatures::samples_seen() const noexcept { return engine_->seen; }
void BlockFeatures::reset() noexcept { engine_->reset(); }
const FeatureParams& BlockFeatures::params() const noexcept { return engine_->params; }
bool BlockFeatures::incremental() const noexcept { return engine_->batches.has_value(); }

}  // namespace leakmon::dsp
