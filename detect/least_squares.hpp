// Ordinary least squares with a fixed number of regressors, accumulated as normal equations:
// constant memory, no allocation, so it can run in the worker thread.
#pragma once

#include <Eigen/Dense>
#include <cstddef>

namespace leakmon::detect {

template <int N>
class LeastSquares {
 public:
  using Vector = Eigen::Matrix<double, N, 1>;

  void add(const Vector& regressors, double y) {
    xtx_.noalias() += regressors * regressors.transpose();
    xty_ += regressors * y;
    yty_ += y * y;
    ++count_;
  }
  std::size_t count() const { return count_; }

  // The coefficients; a tiny ridge keeps a regressor that never varied from blowing up.
  Vector solve() const {
    Eigen::Matrix<double, N, N> a = xtx_;
    const double ridge = 1e-9 * (a.trace() / N + 1e-300);
    a.diagonal().array() += ridge;
    return a.ldlt().solve(xty_);
  }

  // (X'X)^-1 with solve()'s ridge: a block's leverage x' (X'X)^-1 x is how far its regressors lie
  // from those the coefficients were fitted on (1 at most for the blocks fitted).
  Eigen::Matrix<double, N, N> inverse_normal() const {
    Eigen::Matrix<double, N, N> a = xtx_;
    const double ridge = 1e-9 * (a.trace() / N + 1e-300);
    a.diagonal().array() += ridge;
    return a.ldlt().solve(Eigen::Matrix<double, N, N>::Identity());
  }

  // Residual variance of the fitted model (unbiased).
  double residual_variance(const Vector& beta) const {
    if (count_ <= static_cast<std::size_t>(N)) return 0.0;
    const double rss = yty_ - 2.0 * beta.dot(xty_) + beta.dot(xtx_ * beta);
    return rss > 0.0 ? rss / static_cast<double>(count_ - N) : 0.0;
  }

  void clear() {
    xtx_.setZero();
    xty_.setZero();
    yty_ = 0.0;
    count_ = 0;
  }

 private:
  Eigen::Matrix<double, N, N> xtx_ = Eigen::Matrix<double, N, N>::Zero();
  Vector xty_ = Vector::Zero();
  double yty_ = 0.0;
  std::size_t count_ = 0;
};

}  // namespace leakmon::detect
