// A continuous transfer function discretised by the bilinear (Tustin) transform, run as a
// direct-form-II-transposed filter. Coefficients are computed once at construction; update()
// is a few multiply-adds on fixed-size arrays (no allocation).
#pragma once

#include <array>
#include <cstddef>
#include <initializer_list>

namespace leakmon::sim {

inline constexpr std::size_t kMaxTransferOrder = 4;

class DiscreteTransferFunction {
 public:
  DiscreteTransferFunction() = default;
  // num, den: coefficients of s in descending powers (den monic or not; deg num <= deg den).
  static DiscreteTransferFunction tustin(std::initializer_list<double> num,
                                         std::initializer_list<double> den, double sample_rate_hz);

  double update(double input) noexcept;
  void reset() noexcept { state_.fill(0.0); }
  std::size_t order() const { return order_; }
  // z-domain coefficients in descending powers of z, normalised so that a[0] = 1.
  const std::array<double, kMaxTransferOrder + 1>& b() const { return b_; }
  const std::array<double, kMaxTransferOrder + 1>& a() const { return a_; }

 private:
  std::size_t order_ = 0;
  std::array<double, kMaxTransferOrder + 1> b_{}, a_{};
  std::array<double, kMaxTransferOrder> state_{};
};

}  // namespace leakmon::sim
