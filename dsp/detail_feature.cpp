#include "dsp/detail_feature.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "dsp/dwt.hpp"
#include "dsp/wavelet.hpp"

namespace leakmon::dsp {

void validate(const FeatureParams& params) {
  if (!has_wavelet(params.wavelet)) {
    throw std::invalid_argument(fmt::format(
        "wavelet: unknown wavelet '{}' (offered: haar, db1..db20, sym2..sym20, coif1..coif5)",
        params.wavelet));
  }
  const std::size_t taps = wavelet(params.wavelet).filter_length();
  if (params.step == 0) throw std::invalid_argument("step: must be at least 1 sample, got 0");
  if (params.window < taps) {
    throw std::invalid_argument(
        fmt::format("window: {} samples is shorter than the {} filter ({} taps)", params.window,
                    params.wavelet, taps));
  }
  if (params.level < 1) {
    throw std::invalid_argument(fmt::format("level: must be at least 1, got {}", params.level));
  }
  const int max_level = dwt_max_level(params.window, taps);
  if (params.level > max_level) {
    throw std::invalid_argument(fmt::format(
        "level: {} is above the maximum level {} for a {}-sample window with {} ({} taps); every "
        "coefficient would depend on the boundary extension",
        params.level, max_level, params.window, params.wavelet, taps));
  }
  if (mode_name(params.mode) == "unknown") {
    throw std::invalid_argument(
        fmt::format("mode: value {} is not an extension mode", static_cast<int>(params.mode)));
  }
}

}  // namespace leakmon::dsp
