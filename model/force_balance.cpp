#include "model/force_balance.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <vector>

#include "model/piston_velocity.hpp"
#include "sim/friction.hpp"

namespace leakmon::model {
namespace {

constexpr int kMaxUnknowns = 7;  // m, b, F_C, constant, p1 lag, p2 lag (, K_s)

double velocity(const MeasuredRecord& r, std::size_t k) { return PistonVelocity::at(r.x, k, r.dt); }

// The friction regressor's sign of v: PistonVelocity::line_at says why not the cubic.
double friction_velocity(const MeasuredRecord& r, std::size_t k) {
  return PistonVelocity::line_at(r.x, k, r.dt);
}

}  // namespace

bool usable(const ForceBalance& estimate, double stated_m) {
  return estimate.windows >= 100 && estimate.m >= 0.6 * stated_m && estimate.m <= 1.4 * stated_m &&
         estimate.m_error < 0.1 * estimate.m;
}

ForceBalance estimate_force_balance(const MeasuredRecord& record, std::span<const Segment> segments,
                                    const sim::Parameters& rig, std::size_t window_samples,
                                    bool free_stiffness) {
  const double area = rig.A();
  const int unknowns = free_stiffness ? kMaxUnknowns : kMaxUnknowns - 1;
  const double spring = free_stiffness ? 0.0 : rig.K_s;
  std::vector<std::array<double, kMaxUnknowns + 1>> rows;
  for (const auto& seg : segments) {
    // Segments are gap-free with PistonVelocity::kHalfWindow valid samples on either side.
    for (std::size_t a = seg.begin; a + window_samples < seg.begin + seg.length;
         a += window_samples) {
      const std::size_t z = a + window_samples;
      double load = 0.0, friction = 0.0, displacement = 0.0;
      for (std::size_t k = a; k < z; ++k) {  // trapezoidal integrals over [t_a, t_z]
        const auto force = [&](std::size_t j) {
          return area * (record.p1[j] - record.p2[j]) - spring * record.x[j];
        };
        load += 0.5 * record.dt * (force(k) + force(k + 1));
        displacement += 0.5 * record.dt * (record.x[k] + record.x[k + 1]);
        friction += 0.5 * record.dt *
                    (sim::coulomb_friction(1.0, friction_velocity(record, k)) +
                     sim::coulomb_friction(1.0, friction_velocity(record, k + 1)));
      }
      const double span = static_cast<double>(window_samples) * record.dt;
      std::array<double, kMaxUnknowns + 1> row{velocity(record, z) - velocity(record, a),
                                               record.x[z] - record.x[a],
                                               friction,
                                               span,
                                               area * (record.p1[z] - record.p1[a]),
                                               -area * (record.p2[z] - record.p2[a]),
                                               displacement,
                                               0.0};
      row[static_cast<std::size_t>(unknowns)] = load;  // the right-hand side after the unknowns
      rows.push_back(row);
    }
  }
  ForceBalance out;
  out.windows = rows.size();
  if (rows.size() < 4 * static_cast<std::size_t>(unknowns)) {
    // Too few windows to regress on: an unknown spring stays unknown (not the 0 it would read).
    out.K_s = free_stiffness ? std::nan("") : rig.K_s;
    return out;
  }
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), unknowns);
  Eigen::VectorXd y(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int j = 0; j < unknowns; ++j) {
      a(static_cast<Eigen::Index>(i), j) = rows[i][static_cast<std::size_t>(j)];
    }
    y(static_cast<Eigen::Index>(i)) = rows[i][static_cast<std::size_t>(unknowns)];
  }
  // Column scaling keeps the normal equations well conditioned (velocities vs seconds).
  const Eigen::VectorXd scale = a.colwise().norm().cwiseMax(1e-300).transpose();
  const Eigen::MatrixXd scaled = a * scale.cwiseInverse().asDiagonal();
  const Eigen::VectorXd theta_scaled = scaled.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd theta = theta_scaled.cwiseQuotient(scale);
  const Eigen::VectorXd residual = y - a * theta;
  const double s2 = residual.squaredNorm() /
                    static_cast<double>(rows.size() - static_cast<std::size_t>(unknowns));
  const Eigen::MatrixXd cov =
      s2 * (scaled.transpose() * scaled).inverse();  // in scaled coordinates
  out.m = theta(0);
  out.b = theta(1);
  out.m_error = std::sqrt(std::max(cov(0, 0), 0.0)) / scale(0);
  out.b_error = std::sqrt(std::max(cov(1, 1), 0.0)) / scale(1);
  out.constant = theta(3);
  out.constant_error = std::sqrt(std::max(cov(3, 3), 0.0)) / scale(3);
  out.K_s = rig.K_s;
  if (free_stiffness) {
    // The spring's force moved to the left-hand side: K_s int x dt.
    out.K_s = theta(6);
    out.K_s_error = std::sqrt(std::max(cov(6, 6), 0.0)) / scale(6);
  }
  return out;
}

}  // namespace leakmon::model
