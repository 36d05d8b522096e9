#include "sim/transfer_function.hpp"

#include <stdexcept>
#include <vector>

namespace leakmon::sim {
namespace {

using Polynomial = std::vector<double>;  // descending powers; construction only

Polynomial multiply(const Polynomial& a, const Polynomial& b) {
  Polynomial product(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) product[i + j] += a[i] * b[j];
  }
  return product;
}

Polynomial power(const Polynomial& base, std::size_t exponent) {
  Polynomial result{1.0};
  for (std::size_t i = 0; i < exponent; ++i) result = multiply(result, base);
  return result;
}

// P(s) of degree <= n with s = k (z - 1)/(z + 1), multiplied through by (z + 1)^n:
// sum_i c_i k^(n-i) (z - 1)^(n-i) (z + 1)^i, c in descending powers padded to n + 1 terms.
Polynomial bilinear(const Polynomial& c, std::size_t n, double k) {
  Polynomial padded(n + 1 - c.size(), 0.0);
  padded.insert(padded.end(), c.begin(), c.end());
  Polynomial z(n + 1, 0.0);
  double k_power = 1.0;
  for (std::size_t degree = 0; degree <= n; ++degree) {  // degree of s in this term
    const double coefficient = padded[n - degree] * k_power;
    const Polynomial term = multiply(power({1.0, -1.0}, degree), power({1.0, 1.0}, n - degree));
    for (std::size_t j = 0; j <= n; ++j) z[j] += coefficient * term[j];
    k_power *= k;
  }
  return z;
}

}  // namespace

DiscreteTransferFunction DiscreteTransferFunction::tustin(std::initializer_list<double> num,
                                                          std::initializer_list<double> den,
                                                          double sample_rate_hz) {
  const Polynomial numerator(num), denominator(den);
  if (denominator.empty() || denominator.front() == 0.0 || numerator.size() > denominator.size() ||
      denominator.size() > kMaxTransferOrder + 1) {
    throw std::invalid_argument("transfer function must be proper, of order <= 4");
  }
  const std::size_t n = denominator.size() - 1;
  const double k = 2.0 * sample_rate_hz;
  const Polynomial b = bilinear(numerator, n, k);
  const Polynomial a = bilinear(denominator, n, k);
  DiscreteTransferFunction tf;
  tf.order_ = n;
  for (std::size_t j = 0; j <= n; ++j) {
    tf.b_[j] = b[j] / a[0];
    tf.a_[j] = a[j] / a[0];
  }
  return tf;
}

double DiscreteTransferFunction::update(double input) noexcept {
  // Direct form II transposed.
  const double output = b_[0] * input + (order_ > 0 ? state_[0] : 0.0);
  for (std::size_t i = 0; i + 1 < order_; ++i) {
    state_[i] = b_[i + 1] * input - a_[i + 1] * output + state_[i + 1];
  }
  if (order_ > 0) state_[order_ - 1] = b_[order_] * input - a_[order_] * output;
  return output;
}

}  // namespace leakmon::sim
