// Sensor faults through the daemon's pipeline (replay_capture, as `leakmon replay` runs it):
// a frozen p1 is named as a sensor_fault within 5 s and never becomes internal_leakage; the
// detector keeps what it learned, so a leak that opens after the fault is still found; a spike is
// named at once and, replaced, changes nothing else. The per-sample path allocates nothing.
// Captures come from sim:: and are corrupted here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "daemon/config.hpp"
#include "pipeline/actuator_monitor.hpp"
#include "pipeline/event_log.hpp"
#include "pipeline/replay.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/alloc_counter.hpp"

namespace leakmon::pipeline {
namespace {

using capture::Role;

constexpr double kRate = 500.0;
// The default detector settles 2 s and learns 90 s; the fault comes after that, the leak later.
constexpr double kFreezeFrom = 120.0, kFreezeTo = 150.0, kLeakOnset = 210.0;

capture::Capture capture(std::uint64_t seed, std::string_view preset, double duration,
                         std::optional<double> leak_onset) {
  sim::Scenario scenario = sim::preset(preset, seed);
  scenario.duration_s = duration;
  scenario.effects.internal_leakage.reset();
  if (leak_onset) {
    sim::InternalLeakage leak;
    leak.C_L = 2.5e-12;  // 0.15 l/min/MPa, as in replay_test
    leak.onset_s = *leak_onset;
    scenario.effects.internal_leakage = leak;
  }
  return sim::simulate(scenario);
}

std::size_t row_at(double t) { return static_cast<std::size_t>(std::lround(t * kRate)); }

void freeze(capture::Capture& c, const std::string& channel, double from, double to) {
  auto& v = c.column(channel);
  for (std::size_t i = row_at(from); i < row_at(to) && i < v.size(); ++i)
    v[i] = v[row_at(from) - 1];
}

void drop(capture::Capture& c, const std::string& channel, double from, double to) {
  auto& v = c.column(channel);
  for (std::size_t i = row_at(from); i < row_at(to) && i < v.size(); ++i) v[i] = NAN;
}

// The acquisition loses every channel at once (a driver reconnecting).
void outage(capture::Capture& c, double from, double to) {
  for (const char* name : {"p1", "p2", "x", "u"}) drop(c, name, from, to);
}

std::vector<io::Event> events_of(const ReplayResult& r, io::EventKind kind,
                                 const std::string& alarm) {
  std::vector<io::Event> out;
  std::copy_if(r.events.begin(), r.events.end(), std::back_inserter(out),
               [&](const io::Event& e) { return e.kind == kind && e.alarm == alarm; });
  return out;
}

TEST(SensorFaultReplay, FrozenP1IsNamedNotMistakenForALeakAndNothingIsRelearned) {
  for (auto [preset, seed] : {std::pair{"healthy", 11u}, std::pair{"healthy-ft", 12u}}) {
    SCOPED_TRACE(preset);
    const capture::Capture clean = capture(seed, preset, 300.0, kLeakOnset);
    capture::Capture frozen = clean;
    freeze(frozen, "p1", kFreezeFrom, kFreezeTo);

    const ReplayResult result = replay_capture(frozen, default_replay_config(frozen));
    const auto faults = events_of(result, io::EventKind::alarm_raised, "sensor_fault");
    ASSERT_EQ(faults.size(), 1u);
    EXPECT_EQ(faults[0].channel, "p1");
    EXPECT_EQ(faults[0].fault, "frozen");
    EXPECT_GE(faults[0].t, kFreezeFrom);
    EXPECT_LE(faults[0].t, kFreezeFrom + 5.0);
    const std::string line = to_json_line(faults[0]);
    EXPECT_NE(line.find("\"alarm\": \"sensor_fault\""), std::string::npos) << line;
    EXPECT_NE(line.find("\"channel\": \"p1\""), std::string::npos) << line;
    EXPECT_NE(line.find("\"fault\": \"frozen\""), std::string::npos) << line;
    const auto cleared = events_of(result, io::EventKind::alarm_cleared, "sensor_fault");
    ASSERT_EQ(cleared.size(), 1u);
    EXPECT_GE(cleared[0].t, kFreezeTo);
    EXPECT_LE(cleared[0].t, kFreezeTo + 5.0);

    const auto leaks = events_of(result, io::EventKind::alarm_raised, "internal_leakage");
    ASSERT_FALSE(leaks.empty()) << "the leak after the fault was not found";
    EXPECT_GT(leaks.front().t, kLeakOnset) << "internal_leakage raised by the frozen sensor";

    // Without relearning, the leak is found about as fast as on the unfaulted capture.
    const ReplayResult reference = replay_capture(clean, default_replay_config(clean));
    const auto reference_leaks =
        events_of(reference, io::EventKind::alarm_raised, "internal_leakage");
    ASSERT_FALSE(reference_leaks.empty());
    std::printf(
        "%s: sensor_fault p1 frozen after %.2f s, cleared %.2f s after recovery; leak "
        "found %.1f s after onset (%.1f s without the fault)\n",
        preset, faults[0].t - kFreezeFrom, cleared[0].t - kFreezeTo, leaks.front().t - kLeakOnset,
        reference_leaks.front().t - kLeakOnset);
    EXPECT_LE(leaks.front().t, reference_leaks.front().t + 10.0);
    ASSERT_EQ(result.actuators.size(), 1u);
    const auto& status = result.actuators[0];
    EXPECT_FALSE(status.learning);
    EXPECT_FALSE(status.suspended);
    EXPECT_GT(status.suspended_decisions, 0u);
    ASSERT_EQ(status.channels.size(), 3u);
    for (const auto& c : status.channels) EXPECT_EQ(c.status, io::DeviceStatus::ok) << c.channel;
  }
}

// The same frozen capture with the plausibility check of p1 switched off: what the check
// prevents (so the test above can fail).
TEST(SensorFaultReplay, WithoutTheCheckAFrozenP1LooksLikeALeak) {
  const capture::Capture clean = capture(11, "healthy", 160.0, std::nullopt);
  capture::Capture frozen = clean;
  freeze(frozen, "p1", kFreezeFrom, kFreezeTo);
  DaemonConfig config = default_replay_config(frozen);
  config.actuators[0].transducers[Role::p1].enabled = false;
  const ReplayResult result = replay_capture(frozen, config);
  const auto leaks = events_of(result, io::EventKind::alarm_raised, "internal_leakage");
  ASSERT_FALSE(leaks.empty());
  EXPECT_GE(leaks.front().t, kFreezeFrom);
  EXPECT_TRUE(events_of(result, io::EventKind::alarm_raised, "sensor_fault").empty());
}

// A gap in every channel at once is the acquisition (a driver reconnecting), reported as
// driver_fault by the daemon, not a transducer; one channel missing alone is a dropout.
TEST(SensorFaultReplay, AnOutageOfEveryChannelIsNotASensorFaultButOneMissingChannelIs) {
  const capture::Capture clean = capture(14, "healthy", 160.0, std::nullopt);
  capture::Capture lost = clean;
  outage(lost, 120.0, 122.0);
  const ReplayResult all = replay_capture(lost, default_replay_config(lost));
  EXPECT_TRUE(events_of(all, io::EventKind::alarm_raised, "sensor_fault").empty());
  EXPECT_TRUE(events_of(all, io::EventKind::alarm_raised, "internal_leakage").empty());

  capture::Capture one = clean;
  drop(one, "p2", 120.0, 122.0);
  const ReplayResult single = replay_capture(one, default_replay_config(one));
  const auto faults = events_of(single, io::EventKind::alarm_raised, "sensor_fault");
  ASSERT_EQ(faults.size(), 1u);
  EXPECT_EQ(faults.front().channel, "p2");
  EXPECT_EQ(faults.front().fault, "dropout");
  EXPECT_LT(faults.front().t, 125.0);
  EXPECT_TRUE(events_of(single, io::EventKind::alarm_raised, "internal_leakage").empty());
}

// A flaky link: the stream is damaged (a spike is named on p1), then the link dies. The outage is
// still the acquisition's, not a dead transducer, even though p1 had a fault announced already.
TEST(SensorFaultReplay, AnOutageAfterASpikeIsNotADropout) {
  const capture::Capture clean = capture(15, "healthy", 160.0, std::nullopt);
  capture::Capture flaky = clean;
  flaky.column("p1")[row_at(119.0)] += 3e6;
  outage(flaky, 120.0, 122.0);
  const ReplayResult result = replay_capture(flaky, default_replay_config(flaky));
  const auto faults = events_of(result, io::EventKind::alarm_raised, "sensor_fault");
  ASSERT_EQ(faults.size(), 1u);
  EXPECT_EQ(faults.front().channel, "p1");
  EXPECT_EQ(faults.front().fault, "spikes");
  EXPECT_TRUE(events_of(result, io::EventKind::alarm_raised, "internal_leakage").empty());
}

TEST(SensorFaultReplay, SpikesAreNamedAtOnceWithoutChangingTheLeakDecision) {
  const capture::Capture clean = capture(13, "healthy", 240.0, kLeakOnset - 60.0);
  capture::Capture spiky = clean;
  auto& p1 = spiky.column("p1");
  // One 3 MPa spike every 75 s: each a `spikes` fault of its own (it clears after a quiet
  // minute), each sample replaced, so the leak decision goes on as without them.
  std::size_t spikes = 0;
  for (double t = 40.0; t < 240.0; t += 75.0, ++spikes) p1[row_at(t)] += 3e6;

  const ReplayResult a = replay_capture(clean, default_replay_config(clean));
  const ReplayResult b = replay_capture(spiky, default_replay_config(spiky));
  const auto named = events_of(b, io::EventKind::alarm_raised, "sensor_fault");
  ASSERT_EQ(named.size(), spikes);
  for (std::size_t k = 0; k < spikes; ++k) {
    EXPECT_EQ(named[k].channel, "p1");
    EXPECT_EQ(named[k].fault, "spikes");
    EXPECT_NEAR(named[k].t, 40.0 + 75.0 * static_cast<double>(k), 0.05);
  }
  const auto leaks_a = events_of(a, io::EventKind::alarm_raised, "internal_leakage");
  const auto leaks_b = events_of(b, io::EventKind::alarm_raised, "internal_leakage");
  ASSERT_FALSE(leaks_a.empty());
  ASSERT_EQ(leaks_b.size(), leaks_a.size());
  EXPECT_NEAR(leaks_b.front().t, leaks_a.front().t, 0.5);
  EXPECT_GT(leaks_b.front().t, kLeakOnset - 60.0);
  ASSERT_EQ(b.actuators.size(), 1u);
  EXPECT_EQ(b.actuators[0].channels.at(0).channel, "p1");
  EXPECT_EQ(b.actuators[0].channels.at(0).spikes_rejected, spikes);
  EXPECT_EQ(b.actuators[0].decisions, a.actuators[0].decisions) << "a hop was suspended";
  EXPECT_NEAR(b.actuators[0].score, a.actuators[0].score,
              0.05 * std::abs(a.actuators[0].score) + 1e-9);
}

TEST(SensorFaultMonitor, PerSamplePathAllocatesNothing) {
  capture::Capture c = capture(14, "healthy", 40.0, std::nullopt);
  auto& p1 = c.column("p1");
  // A rejected spike inside the measured stretch; the one before it has announced the `spikes`
  // fault already (an alarm event allocates), which the second one keeps up.
  p1[row_at(15.0)] += 3e6;
  p1[row_at(25.0)] += 3e6;
  const DaemonConfig config = default_replay_config(c);
  const auto& actuator = config.actuators.at(0);
  ChannelLayout layout;
  std::vector<const std::vector<double>*> columns;
  for (const Role role : {Role::p1, Role::p2, Role::u, Role::x, Role::xref}) {
    const std::string column(capture::to_string(role));
    if (!c.has(column)) continue;
    layout.index[role] = static_cast<int>(columns.size());
    columns.push_back(&c.column(column));
  }
  ActuatorMonitor monitor(actuator, layout, 2'000'000);
  std::size_t events = 0;
  const EventPublisher publish = [&](const io::Event&) { ++events; };
  auto push_rows = [&](std::size_t from, std::size_t to) {
    std::size_t decisions = 0;
    realtime::Sample sample;
    for (std::size_t i = from; i < to; ++i) {
      sample.t = c.column("t")[i];
      sample.tick = i;
      for (std::size_t k = 0; k < columns.size(); ++k) sample.values[k] = (*columns[k])[i];
      decisions += monitor.push(sample, publish) ? 1 : 0;
    }
    return decisions;
  };
  push_rows(0, row_at(20.0));  // warm-up: windows filled, detector past its settling
  std::size_t decisions = 0;
  {
    test::AllocationScope scope;
    decisions = push_rows(row_at(20.0), row_at(40.0));
    EXPECT_EQ(scope.count(), 0u);
  }
  EXPECT_GT(decisions, 400u);
  EXPECT_EQ(events, 1u);  // the first spike's sensor_fault
  EXPECT_EQ(monitor.status().channels.at(0).spikes_rejected, 2u);
}

TEST(SensorFaultConfig, TransducersAreConfigurablePerChannel) {
  const auto config = daemon::parse_config(
      config::ConfigNode::load_string("drivers: [{name: rig, type: sim, scenario: healthy}]\n"
                                      "actuators:\n"
                                      "  - name: a\n"
                                      "    channels: {p1: p1, p2: p2, x: x}\n"
                                      "    transducers:\n"
                                      "      p1: {max: 35.0e6, bits: 16, noise_sigma: 2000}\n"
                                      "      x: {check: false}\n",
                                      "rig.yaml"));
  const auto& a = config.actuators.at(0);
  EXPECT_DOUBLE_EQ(a.transducers[Role::p1].max, 35e6);
  EXPECT_DOUBLE_EQ(a.transducers[Role::p1].resolution, 35e6 / 65536.0);
  EXPECT_DOUBLE_EQ(a.transducers[Role::p1].noise_sigma, 2000.0);
  EXPECT_DOUBLE_EQ(a.transducers[Role::p2].max, 20.7e6) << "MODEL.md's transducer by default";
  EXPECT_FALSE(a.transducers[Role::x].enabled);
  try {
    daemon::parse_config(
        config::ConfigNode::load_string("drivers: [{name: rig, type: sim, scenario: healthy}]\n"
                                        "actuators:\n"
                                        "  - name: a\n"
                                        "    channels: {p1: p1}\n"
                                        "    transducers: {p1: {min: 5, max: 1}}\n",
                                        "rig.yaml"));
    FAIL() << "no error for max below min";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.yaml:5:"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace leakmon::pipeline
