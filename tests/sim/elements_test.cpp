// The elements one by one against analytic values: Tustin discretisation, the controllers,
// the reference, the flow noise, the sensor chain, the orifice and valve laws, the spool.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "sim/chamber.hpp"
#include "sim/controller.hpp"
#include "sim/flow_noise.hpp"
#include "sim/plant.hpp"
#include "sim/reference.hpp"
#include "sim/sensors.hpp"
#include "sim/supply.hpp"
#include "sim/transfer_function.hpp"
#include "sim/valve.hpp"

namespace leakmon::sim {
namespace {

using Complex = std::complex<double>;

Complex polynomial(const std::vector<double>& c, Complex x) {
  Complex value = 0.0;
  for (double coefficient : c) value = value * x + coefficient;
  return value;
}

// Steady-state response of the discrete filter to a sinusoid, measured by running it.
Complex measured_response(DiscreteTransferFunction tf, double f, double fs) {
  const double omega = 2.0 * std::numbers::pi * f / fs;
  Complex acc = 0.0;
  const int settle = 20000, cycles = 4000;
  for (int k = 0; k < settle + cycles; ++k) {
    const double y = tf.update(std::cos(omega * k));
    if (k >= settle) acc += y * std::exp(Complex(0.0, -omega * k));
  }
  return 2.0 * acc / static_cast<double>(cycles);
}

// Tustin maps z = e^{jwT} to s = j (2/T) tan(wT/2): the discrete response at w equals the
// continuous one at the warped frequency.
TEST(Tustin, DiscreteResponseIsTheContinuousResponseAtTheWarpedFrequency) {
  const double fs = 500.0;
  const std::vector<double> num = {246.59, 7.18e3, 4.78e7, 5.49e8};
  const std::vector<double> den = {1.0, 420.0, 9e4, 0.0};
  const auto tf = DiscreteTransferFunction::tustin({246.59, 7.18e3, 4.78e7, 5.49e8},
                                                   {1.0, 420.0, 9e4, 0.0}, fs);
  for (double f : {1.0, 10.0, 40.0, 100.0}) {
    const double warped = 2.0 * fs * std::tan(std::numbers::pi * f / fs);
    const Complex s(0.0, warped);
    const Complex expected = polynomial(num, s) / polynomial(den, s);
    const Complex z = std::exp(Complex(0.0, 2.0 * std::numbers::pi * f / fs));
    const auto& b = tf.b();
    const auto& a = tf.a();
    const Complex from_coefficients =
        polynomial({b[0], b[1], b[2], b[3]}, z) / polynomial({a[0], a[1], a[2], a[3]}, z);
    EXPECT_NEAR(std::abs(from_coefficients - expected) / std::abs(expected), 0.0, 1e-9) << f;
  }
  const auto prefilter = DiscreteTransferFunction::tustin({100.0}, {1.0, 100.0}, fs);
  const double f = 20.0;
  const Complex s(0.0, 2.0 * fs * std::tan(std::numbers::pi * f / fs));
  const Complex expected = 100.0 / (s + 100.0);
  EXPECT_NEAR(std::abs(measured_response(prefilter, f, fs) - expected), 0.0, 1e-6);
}

// DC gains of the paper's loops: basic G(0) = 2.76e6 * 25 / (16 * 120^2); both prefilters 1.
TEST(Controllers, BasicLoopHasThePapersDcGainAndSaturatesAtTenVolts) {
  Controller basic(ControllerKind::basic, 500.0);
  double u = 0.0;
  for (int k = 0; k < 5000; ++k) u = basic.update(1e-3, 0.0);
  EXPECT_NEAR(basic.filtered_reference(), 1e-3, 1e-12);
  EXPECT_NEAR(u, 2.76e6 * 25.0 / (16.0 * 14400.0) * 1e-3, 1e-9);
  for (int k = 0; k < 100; ++k) u = basic.update(0.05, -0.05);
  EXPECT_EQ(u, 10.0);
  basic.reset();
  EXPECT_EQ(basic.update(0.0, 0.0), 0.0);
}

TEST(Controllers, FaultTolerantLoopIntegratesAConstantError) {
  Controller ft(ControllerKind::fault_tolerant, 500.0);
  // G has a pole at s = 0: a constant error makes u ramp until it saturates.
  double u_early = 0.0, u_late = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const double u = ft.update(1e-4, 0.0);
    if (k == 1000) u_early = u;
    u_late = u;
  }
  EXPECT_GT(u_late, u_early);
  // Slope 5.49e8 / 9e4 per second per metre of error, once the prefilter has settled.
  Controller ft2(ControllerKind::fault_tolerant, 500.0);
  std::vector<double> u(3000);
  for (auto& value : u) value = ft2.update(1e-5, 0.0);
  const double slope = (u[2999] - u[2499]) / 1.0;
  EXPECT_NEAR(slope, 5.49e8 / 9e4 * 1e-5, 1e-3 * 5.49e8 / 9e4 * 1e-5);
}

TEST(ReferenceSteps, AreReproducibleAndWithinThePapersRanges) {
  const ReferenceSettings settings;
  Reference a(settings, 42), b(settings, 42), c(settings, 43);
  int changes = 0, positive = 0, levels = 0;
  double last = 0.0, last_change = 0.0, shortest = 1e9, longest = 0.0;
  bool differs = false;
  for (int k = 0; k < 500 * 600; ++k) {
    const double t = k * 0.002;
    const double r = a.at(t);
    ASSERT_EQ(r, b.at(t));
    differs |= r != c.at(t);
    ASSERT_GE(std::abs(r), settings.amp_min);
    ASSERT_LE(std::abs(r), settings.amp_max);
    if (k == 0 || r != last) {
      if (k > 0) {
        ++changes;
        shortest = std::min(shortest, t - last_change);
        longest = std::max(longest, t - last_change);
      }
      last_change = t;
      ++levels;
      positive += r > 0;
    }
    last = r;
  }
  EXPECT_TRUE(differs);
  EXPECT_GE(shortest, settings.hold_min - 0.002);
  EXPECT_LE(longest, settings.hold_max + 0.002);
  // 600 s of holds averaging 2.25 s: about 267 levels, about half positive.
  EXPECT_GT(changes, 200);
  EXPECT_LT(changes, 340);
  EXPECT_NEAR(static_cast<double>(positive) / levels, 0.5, 0.1);
}

// The OU process has the variance and correlation time of MODEL.md, and its values depend on
// time only, not on how often it is sampled.
TEST(FlowNoise, HasTheOrnsteinUhlenbeckStatisticsAndIgnoresTheSamplingStep) {
  const double sigma = 0.0015, tau = 1e-3;
  FlowNoise coarse(sigma, tau, kNoiseGridStep, 7), fine(sigma, tau, kNoiseGridStep, 7);
  const int n = 400000;
  double sum = 0.0, square = 0.0, lagged = 0.0;
  const int lag = static_cast<int>(std::lround(tau / kNoiseGridStep));
  std::vector<double> history(lag, 0.0);  // slot k % lag holds w[k - lag]
  for (int k = 0; k < n; ++k) {
    const double t = k * kNoiseGridStep;
    const double w = coarse.at(t);
    for (int j = 1; j <= 4; ++j) fine.at(t - kNoiseGridStep + j * kNoiseGridStep / 4);
    ASSERT_DOUBLE_EQ(w, fine.at(t));
    sum += w;
    square += w * w;
    if (k >= lag) lagged += w * history[k % lag];
    history[k % lag] = w;
  }
  const double mean = sum / n;
  const double variance = square / n - mean * mean;
  EXPECT_NEAR(std::sqrt(variance), sigma, 0.03 * sigma);
  EXPECT_NEAR(lagged / (n - lag) / variance, std::exp(-1.0), 0.03);
}

TEST(SensorChain, QuantisesTo12BitsClampsAndAddsTheOffsetBeforeNoise) {
  SensorSettings settings;
  settings.pressure_noise_sigma = 0.0;
  settings.position_noise_sigma = 0.0;
  const double lsb = settings.pressure_lsb();
  EXPECT_NEAR(lsb, 20.7e6 / 4096.0, 1e-9);
  EXPECT_NEAR(lsb, 5.05e3, 5.0);
  Effects effects;
  effects.sensor_offset = SensorOffset{2e5, PressureChannel::p2};
  Sensors sensors(settings, effects, 1);
  const Measurement m = sensors.measure(0.012344, 8.0e6 + 0.4 * lsb, 3.0e7);
  EXPECT_NEAR(m.p1, std::round((8.0e6 + 0.4 * lsb) / lsb) * lsb, 1e-6);
  EXPECT_NEAR(m.p2, 4095.0 * lsb, 1e-6);  // clamped at the top of the range
  EXPECT_NEAR(m.x, 0.01234, 1e-12);
  const Measurement low = sensors.measure(0.0, -1e5, 1.0e6);
  EXPECT_EQ(low.p1, 0.0);
  EXPECT_NEAR(low.p2, std::round(1.2e6 / lsb) * lsb, 1e-6);  // offset applies to p2 only

  SensorSettings noisy;  // defaults: sigma 5 kPa, 5 um
  noisy.pressure_quantisation = noisy.position_quantisation = false;
  Sensors noisy_sensors(noisy, {}, 3);
  double square_p = 0.0, square_x = 0.0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const Measurement r = noisy_sensors.measure(0.0, 1e7, 1e7);
    square_p += (r.p1 - 1e7) * (r.p1 - 1e7);
    square_x += r.x * r.x;
  }
  EXPECT_NEAR(std::sqrt(square_p / n), 5e3, 150.0);
  EXPECT_NEAR(std::sqrt(square_x / n), 5e-6, 1.5e-7);

  SensorSettings off;
  off.enabled = false;
  Sensors ideal(off, {}, 3);
  const Measurement exact = ideal.measure(0.0123456, 1234567.8, 7654321.0);
  EXPECT_EQ(exact.x, 0.0123456);
  EXPECT_EQ(exact.p1, 1234567.8);
}

TEST(Valve, OrificeLawIsContinuousAndLaminarNearZero) {
  const double dp_lin = 2e5;
  EXPECT_NEAR(orifice(dp_lin, dp_lin), std::sqrt(dp_lin), 1e-9);
  EXPECT_NEAR(orifice(dp_lin * (1 - 1e-12), dp_lin), std::sqrt(dp_lin), 1e-6);
  EXPECT_NEAR(orifice(-4e6, dp_lin), -2000.0, 1e-9);
  EXPECT_NEAR(orifice(1e5, dp_lin), 1e5 / std::sqrt(dp_lin), 1e-9);
  // Null leakage at o = 0 with p1 = p2 = (ps + pt)/2: every land flow cancels.
  const ValveFlows rest = valve_flows(0.0, 17.2e6, 0.1e6, 8.65e6, 8.65e6, 3.39e-7, dp_lin, 5e-13);
  EXPECT_NEAR(rest.q1, 0.0, 1e-18);
  EXPECT_NEAR(rest.q2, 0.0, 1e-18);
  // Full opening with 7 MPa across each land: 38 l/min at 70 bar total is Kv sqrt(3.5e6).
  const ValveFlows open =
      valve_flows(1.0, 17.2e6, 0.1e6, 17.2e6 - 3.5e6, 0.1e6 + 3.5e6, 3.39e-7, dp_lin, 0.0);
  EXPECT_NEAR(open.q1 * 60000.0, 3.39e-7 * std::sqrt(3.5e6) * 60000.0, 1e-9);
  EXPECT_NEAR(open.q1 * 60000.0, 38.0, 0.1);
  EXPECT_NEAR(open.q2, -open.q1, 1e-12);
  EXPECT_NEAR(overlapped_opening(0.015, 0.02), 0.0, 0.0);
  EXPECT_NEAR(overlapped_opening(-0.05, 0.02), -0.03, 1e-15);
}

TEST(Supply, DroopSolvesTheAlgebraicLoop) {
  const SupplyInputs in{0.8, 6e6, 9e6, 0.1e6, 3.39e-7, 2e5, 5e-13};
  for (const double R_s : {5e9, 3e10, 1e12}) {
    const double ps = drooped_supply(17.2e6, R_s, in);
    EXPECT_NEAR(ps + R_s * supply_flow(ps, in), 17.2e6, 1e-6 * 17.2e6) << R_s;
    EXPECT_LT(ps, 17.2e6);
    EXPECT_GT(ps, in.p1);  // flow still leaves the supply
  }
}

TEST(EntrainedAir, BulkModulusIsLowestAtLowPressureAndTendsToBeta) {
  const double beta = 700e6;
  EXPECT_NEAR(entrained_air_bulk_modulus(beta, 0.0, 1e6), beta, 1e-6);
  const double low = entrained_air_bulk_modulus(beta, 0.1, 0.5e6);
  const double high = entrained_air_bulk_modulus(beta, 0.1, 15e6);
  EXPECT_LT(low, 0.5 * beta);
  EXPECT_GT(high, 0.7 * beta);
  EXPECT_LT(high, beta * 1.0001);
  EXPECT_LT(entrained_air_bulk_modulus(beta, 0.2, 0.5e6), low);
}

// The spool is first order: from rest a held command c gives xs = c (1 - exp(-t / tau)).
TEST(Spool, FollowsTheFirstOrderLawWithTheNominalOrLaggedTimeConstant) {
  for (const double tau : {2.5e-3, 0.012}) {
    Parameters p;
    p.sigma_w = 0.0;
    Effects effects;
    if (tau != p.tau) effects.spool_lag = SpoolLag{tau};
    Plant plant(p, effects, 1, 2.5e-4);
    for (int k = 0; k < 5; ++k) {
      plant.advance(4.0, k * 0.002, 0.002);
      const double t = (k + 1) * 0.002;
      EXPECT_NEAR(plant.state().xs, 0.4 * (1.0 - std::exp(-t / tau)), 1e-6) << tau;
    }
    plant.advance(25.0, 0.01, 0.1);  // beyond u_max the spool saturates at full travel
    EXPECT_NEAR(plant.state().xs, 1.0, 1e-3);
    EXPECT_GT(plant.state().xs, 0.99);
  }
}

}  // namespace
}  // namespace leakmon::sim
