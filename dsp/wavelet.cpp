#include "dsp/wavelet.hpp"

#include <fmt/format.h>

#include <array>
#include <stdexcept>

#include "dsp/wavelet_tables.hpp"

namespace leakmon::dsp {
namespace {

// Built once from the generated tables; the tables themselves are constexpr data.
const std::vector<Wavelet>& catalogue() {
  static const std::vector<Wavelet> wavelets = [] {
    std::vector<Wavelet> list;
    for (const auto& bank : tables::filter_banks()) {
      list.push_back({bank.name, bank.dec_lo, bank.dec_hi, bank.rec_lo, bank.rec_hi});
    }
    return list;
  }();
  return wavelets;
}

const Wavelet* find(std::string_view name) {
  for (const auto& w : catalogue()) {
    if (w.name == name) return &w;
  }
  return nullptr;
}

}  // namespace

const Wavelet& wavelet(std::string_view name) {
  if (const Wavelet* w = find(name)) return *w;
  throw std::invalid_argument(fmt::format(
      "wavelet: unknown wavelet '{}' (offered: haar, db1..db20, sym2..sym20, coif1..coif5)", name));
}

bool has_wavelet(std::string_view name) { return find(name) != nullptr; }

std::vector<std::string_view> wavelet_names() {
  std::vector<std::string_view> names;
  for (const auto& w : catalogue()) names.push_back(w.name);
  return names;
}

}  // namespace leakmon::dsp
