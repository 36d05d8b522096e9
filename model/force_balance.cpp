#include "model/force_balance.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <vector>

#include "sim/friction.hpp"

namespace leakmon::model {
namespace {

constexpr int kVelocityHalfWindow = 3;  // as the segment predictor's velocity estimate
constexpr int kUnknowns = 6;            // m, b, F_C, constant, p1 lag, p2 lag

// Velocity from a least-squares line through x over +-3 samples.
double velocity(const MeasuredRecord& r, std::size_t k) {
  double slope = 0.0, weight = 0.0;
  for (int i = -kVelocityHalfWindow; i <= kVelocityHalfWindow; ++i) {
    slope += i * r.x[static_cast<std::size_t>(static_cast<long>(k) + i)];
    weight += i * i;
  }
  return slope / (weight * r.dt);
}

}  // namespace

bool usable(const ForceBalance& estimate) {
  return estimate.windows >= 100 && estimate.m >= 6.0 && estimate.m <= 14.0 &&
         estimate.m_error < 0.1 * estimate.m;
}

ForceBalance estimate_force_balance(const MeasuredRecord& record, std::span<const Segment> segments,
                                    const sim::Parameters& rig, std::size_t window_samples) {
  const double area = rig.A();
  std::vector<std::array<double, kUnknowns + 1>> rows;
  for (const auto& seg : segments) {
    // Segments are gap-free with kVelocityHalfWindow valid samples on either side.
    for (std::size_t a = seg.begin; a + window_samples < seg.begin + seg.length;
         a += window_samples) {
      const std::size_t z = a + window_samples;
      double load = 0.0, friction = 0.0;
      for (std::size_t k = a; k < z; ++k) {  // trapezoidal integrals over [t_a, t_z]
        const auto force = [&](std::size_t j) {
          return area * (record.p1[j] - record.p2[j]) - rig.K_s * record.x[j];
        };
        load += 0.5 * record.dt * (force(k) + force(k + 1));
        friction += 0.5 * record.dt *
                    (sim::coulomb_friction(1.0, velocity(record, k)) +
                     sim::coulomb_friction(1.0, velocity(record, k + 1)));
      }
      const double span = static_cast<double>(window_samples) * record.dt;
      rows.push_back({velocity(record, z) - velocity(record, a), record.x[z] - record.x[a],
                      friction, span, area * (record.p1[z] - record.p1[a]),
                      -area * (record.p2[z] - record.p2[a]), load});
    }
  }
  ForceBalance out;
  out.windows = rows.size();
  if (rows.size() < 4 * kUnknowns) return out;
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), kUnknowns);
  Eigen::VectorXd y(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int j = 0; j < kUnknowns; ++j) {
      a(static_cast<Eigen::Index>(i), j) = rows[i][static_cast<std::size_t>(j)];
    }
    y(static_cast<Eigen::Index>(i)) = rows[i][kUnknowns];
  }
  // Column scaling keeps the normal equations well conditioned (velocities vs seconds).
  const Eigen::VectorXd scale = a.colwise().norm().cwiseMax(1e-300).transpose();
  const Eigen::MatrixXd scaled = a * scale.cwiseInverse().asDiagonal();
  const Eigen::VectorXd theta_scaled = scaled.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd theta = theta_scaled.cwiseQuotient(scale);
  const Eigen::VectorXd residual = y - a * theta;
  const double s2 = residual.squaredNorm() / static_cast<double>(rows.size() - kUnknowns);
  const Eigen::MatrixXd cov =
      s2 * (scaled.transpose() * scaled).inverse();  // in scaled coordinates
  out.m = theta(0);
  out.b = theta(1);
  out.m_error = std::sqrt(std::max(cov(0, 0), 0.0)) / scale(0);
  out.b_error = std::sqrt(std::max(cov(1, 1), 0.0)) / scale(1);
  return out;
}

}  // namespace leakmon::model
