// Sensor faults (MODEL.md "Sensor faults") show in the capture exactly as MODEL.md's table
// describes, in their channel only and only while active: frozen = the last reported
// (quantised) value repeated exactly; saturated = the range end; spikes = isolated samples off
// by the given magnitude at a Poisson rate; dropout = zeros or gaps (NaN, an empty field).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "capture/capture.hpp"
#include "sim/rig.hpp"
#include "sim/simulate.hpp"
#include "tests/model/test_seed.hpp"
#include "tests/sim/sim_test_support.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::sim {
namespace {

constexpr SensorChannel kChannels[] = {SensorChannel::p1, SensorChannel::p2, SensorChannel::x,
                                       SensorChannel::ps, SensorChannel::temp};

// A moving rig with every recorded channel alive: real sensors, a warm-up so that temp moves,
// a supply ramp so that ps moves.
Scenario base(double duration_s, std::uint64_t seed = 21) {
  Scenario s = preset("healthy", seed);
  s.duration_s = duration_s;
  TemperatureProfile warm;
  warm.kind = TemperatureProfile::Kind::warm_up;
  warm.T0 = 30.0;
  warm.T_work = 45.0;
  warm.tau_s = 10.0;
  s.conditions.temperature = warm;
  s.conditions.supply = {{2.0, 15e6, 10.0}};
  s.record.ps = s.record.temp = true;
  return s;
}

double value(const RigSample& s, SensorChannel channel) {
  switch (channel) {
    case SensorChannel::p1:
      return s.p1;
    case SensorChannel::p2:
      return s.p2;
    case SensorChannel::x:
      return s.x;
    case SensorChannel::ps:
      return s.ps;
    case SensorChannel::temp:
      return s.temp;
  }
  return 0.0;
}

// Every other channel, and this one outside [t0, t1), equals the fault-free run bit for bit.
void expect_only_in(const std::vector<RigSample>& faulty, const std::vector<RigSample>& healthy,
                    SensorChannel channel, double t0, double t1) {
  ASSERT_EQ(faulty.size(), healthy.size());
  for (std::size_t k = 0; k < faulty.size(); ++k) {
    ASSERT_EQ(faulty[k].u, healthy[k].u) << "the servo loop must not see the fault";
    for (const SensorChannel c : kChannels) {
      if (c == channel && faulty[k].t >= t0 && faulty[k].t < t1) continue;
      ASSERT_EQ(value(faulty[k], c), value(healthy[k], c))
          << to_string(c) << " at t = " << faulty[k].t << " (fault on " << to_string(channel)
          << ")";
    }
  }
}

std::vector<RigSample> with_fault(Scenario s, const SensorFault& fault) {
  s.faults = {fault};
  return testing::run(s);
}

TEST(SensorFaults, FrozenRepeatsTheLastReportedValueExactly) {
  const Scenario s = base(20.0);
  const auto healthy = testing::run(s);
  for (const SensorChannel channel : kChannels) {
    const SensorFault fault{SensorFault::Kind::frozen, channel, 6.0, 8.0};
    const auto faulty = with_fault(s, fault);
    expect_only_in(faulty, healthy, channel, 6.0, 14.0);
    const double held = value(healthy[2999], channel);  // t = 5.998, the last before the fault
    int distinct_in_healthy = 0;
    for (std::size_t k = 3000; k < 7000; ++k) {
      ASSERT_EQ(value(faulty[k], channel), held) << to_string(channel) << " k " << k;
      distinct_in_healthy += value(healthy[k], channel) != held;
    }
    // The healthy channel moves in that stretch, so the test can fail.
    EXPECT_GT(distinct_in_healthy, 100) << to_string(channel);
  }
}

TEST(SensorFaults, SaturatedSitsAtTheRangeEnd) {
  const Scenario s = base(12.0);
  const auto healthy = testing::run(s);
  for (const SensorChannel channel : kChannels) {
    for (const bool high : {true, false}) {
      SensorFault fault{SensorFault::Kind::saturated, channel, 4.0, 4.0};
      fault.high = high;
      const auto faulty = with_fault(s, fault);
      expect_only_in(faulty, healthy, channel, 4.0, 8.0);
      double end = high ? 20.7e6 : 0.0;
      if (channel == SensorChannel::x) end = (high ? 0.5 : -0.5) * s.params.L;
      if (channel == SensorChannel::temp) end = high ? 150.0 : -50.0;
      for (std::size_t k = 2000; k < 4000; ++k) {
        ASSERT_EQ(value(faulty[k], channel), end) << to_string(channel) << " k " << k;
      }
    }
  }
}

TEST(SensorFaults, DropoutReadsZeroOrLeavesGaps) {
  const Scenario s = base(12.0);
  const auto healthy = testing::run(s);
  for (const SensorChannel channel : kChannels) {
    for (const bool gap : {false, true}) {
      SensorFault fault{SensorFault::Kind::dropout, channel, 3.0, 2.5};
      fault.gap = gap;
      const auto faulty = with_fault(s, fault);
      expect_only_in(faulty, healthy, channel, 3.0, 5.5);
      for (std::size_t k = 1500; k < 2750; ++k) {
        const double v = value(faulty[k], channel);
        if (gap) {
          ASSERT_TRUE(std::isnan(v)) << to_string(channel) << " k " << k;
        } else {
          ASSERT_EQ(v, 0.0) << to_string(channel) << " k " << k;
        }
      }
    }
  }
}

TEST(SensorFaults, SpikesArriveAtTheirRateAndAreOffByTheirMagnitude) {
  const std::uint64_t seed = test::model_test_seed("SensorFaults.Spikes");
  Scenario s = base(150.0, seed);
  s.conditions.temperature->T_work = 40.0;  // keep temp spikes inside the transmitter range
  const auto healthy = testing::run(s);
  const double rate = 40.0;             // per minute
  const double minutes = 120.0 / 60.0;  // the fault's duration
  for (const SensorChannel channel : kChannels) {
    const bool pressure = channel == SensorChannel::p1 || channel == SensorChannel::p2 ||
                          channel == SensorChannel::ps;
    SensorFault fault{SensorFault::Kind::spikes, channel, 20.0, 120.0};
    fault.rate_per_min = rate;
    fault.magnitude = pressure ? 3e6 : channel == SensorChannel::x ? 5e-3 : 20.0;
    const auto faulty = with_fault(s, fault);
    expect_only_in(faulty, healthy, channel, 20.0, 140.0);
    const double tolerance = pressure ? 20.7e6 / 4096.0 : channel == SensorChannel::x ? 1e-5 : 0.1;
    int spikes = 0;
    for (std::size_t k = 0; k < faulty.size(); ++k) {
      const double off = value(faulty[k], channel) - value(healthy[k], channel);
      if (off == 0.0) continue;
      ++spikes;
      // Off by the magnitude (to within one quantisation step), unless the range clipped it.
      const double clipped =
          value(faulty[k], channel) == 0.0 || value(faulty[k], channel) >= 20.7e6 - tolerance;
      if (!clipped) {
        EXPECT_NEAR(std::abs(off), fault.magnitude, tolerance) << to_string(channel);
      }
    }
    // Poisson count: mean 80 for 2 minutes at 40/min; +-4.5 sigma fails about once in 1e5.
    const double mean = rate * minutes;
    std::printf("%s: %d spikes in %.0f min (expected %.0f)\n",
                std::string(to_string(channel)).c_str(), spikes, minutes, mean);
    EXPECT_NEAR(spikes, mean, 4.5 * std::sqrt(mean)) << to_string(channel);
    EXPECT_GT(spikes, 0);
  }
}

TEST(SensorFaults, CaptureShowsGapsAsEmptyFieldsAndNamesTheFault) {
  Scenario s = base(4.0);
  SensorFault dropout{SensorFault::Kind::dropout, SensorChannel::p2, 1.0, 1.0};
  dropout.gap = true;
  s.faults = {dropout, SensorFault{SensorFault::Kind::frozen, SensorChannel::temp, 2.0, 1.0}};
  const std::string path = test::scratch_dir("sim_sensor_faults") + "/gaps.csv";
  simulate_to_file(s, path);
  const capture::Capture capture = capture::read_capture(path);
  EXPECT_EQ(capture.columns,
            (std::vector<std::string>{"t", "xref", "u", "x", "p1", "p2", "q_int", "ps", "temp"}));
  const auto& p2 = capture.column("p2");
  EXPECT_FALSE(std::isnan(p2[499]));
  for (std::size_t k = 500; k < 1000; ++k) ASSERT_TRUE(std::isnan(p2[k])) << k;
  EXPECT_FALSE(std::isnan(p2[1000]));
  std::vector<std::string> described;
  for (const auto& [key, text] : capture.metadata) {
    if (key == "sensor_fault") described.push_back(text);
  }
  ASSERT_EQ(described.size(), 2u);
  EXPECT_EQ(described[0], "dropout channel=p2 start_s=1 duration_s=1 mode=gap");
  EXPECT_EQ(described[1], "frozen channel=temp start_s=2 duration_s=1");
  EXPECT_NE(capture.metadata_value("temperature").value_or("").find("warm_up T0=30 T_work=45"),
            std::string::npos);
  EXPECT_NE(capture.metadata_value("temp_sensor").value_or("").find("resolution 0.1 K"),
            std::string::npos);
  EXPECT_EQ(capture.metadata_value("supply_change"), "t_s=2 ps=1.5e+07 ramp_s=10");
}

TEST(TemperatureTransducer, ReadsLikeAnRtd) {
  Scenario s = base(10.0);
  TemperatureProfile hot;
  hot.T_work = 47.33;
  s.conditions.temperature = hot;
  const auto run = testing::run(s);
  double sum = 0.0, sum2 = 0.0;
  for (const auto& r : run) {
    ASSERT_EQ(r.temp_true, 47.33);
    ASSERT_NEAR(r.temp * 10.0, std::nearbyint(r.temp * 10.0), 1e-9);  // 0.1 K steps
    sum += r.temp;
    sum2 += (r.temp - 47.33) * (r.temp - 47.33);
  }
  const double n = static_cast<double>(run.size());
  EXPECT_NEAR(sum / n, 47.33, 0.01);
  // 0.05 K noise and 0.1 K quantisation: rms error sqrt(0.05^2 + 0.1^2/12) = 0.059 K.
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.059, 0.006);
  // The supply transducer reads the supply on the pressure chain's 12-bit grid.
  const double lsb = 20.7e6 / 4096.0;
  for (const auto& r : run) {
    ASSERT_NEAR(r.ps / lsb, std::nearbyint(r.ps / lsb), 1e-6);
    ASSERT_NEAR(r.ps, r.ps_true, 5.0 * 5e3 + lsb);
  }
}

}  // namespace
}  // namespace leakmon::sim
