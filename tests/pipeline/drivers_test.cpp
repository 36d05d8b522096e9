// The daemon's own drivers against their references: the sim driver reproduces sim::simulate
// sample for sample; the replay driver plays a capture file back exactly, looping with t
// continuing; the capture recorder writes files the replay driver reads back unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "pipeline/capture_recorder.hpp"
#include "io/replay/replay_driver.hpp"
#include "io/sim/sim_driver.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/paths.hpp"

namespace leakmon {
namespace {

TEST(SimDriver, ReproducesTheBatchSimulationWithTheLeakInjectedAtItsTime) {
  sim::Scenario scenario = sim::preset("healthy-ft", 9);
  scenario.duration_s = 4.0;
  sim::InternalLeakage leak;
  leak.C_L = 2.0e-12;
  leak.onset_s = 2.0;
  scenario.effects.internal_leakage = leak;
  const capture::Capture reference = sim::simulate(scenario);

  auto driver = io::make_sim_driver(config::ConfigNode::load_string(
      "{name: rig, type: sim, scenario: healthy-ft, seed: 9, leak: {C_L: 2.0e-12, onset_s: 2}}",
      "test.yaml"));
  driver->start();
  const auto channels = driver->channels();
  std::vector<double> values(channels.size());
  io::Tick tick;
  std::uint64_t allocations = 0;
  bool leaking_seen = false;
  for (std::size_t row = 0; row < reference.rows(); ++row, ++tick.index) {
    test::AllocationScope scope;
    ASSERT_EQ(driver->read(tick, values), io::ReadStatus::ok);
    allocations += scope.count();
    ASSERT_DOUBLE_EQ(*driver->source_time(), reference.column("t")[row]);
    for (std::size_t c = 0; c < channels.size(); ++c) {
      ASSERT_DOUBLE_EQ(values[c], reference.column(channels[c])[row])
          << channels[c] << " at row " << row;
    }
    if (values.back() != 0.0) leaking_seen = true;  // q_int
  }
  EXPECT_EQ(allocations, 0u) << "read() runs on the real-time thread";
  EXPECT_TRUE(leaking_seen) << "the injected leak never flowed";
}

TEST(ReplayDriver, LoopsWithTimeContinuing) {
  capture::Capture capture;
  capture.columns = {"t", "p1", "x"};
  capture.values = {{0.0, 0.002, 0.004}, {1.0, 2.0, 3.0}, {0.1, 0.2, 0.3}};
  io::ReplaySettings settings;
  settings.loop = true;
  settings.channels = {"x"};
  io::ReplayDriver driver(settings, std::make_shared<const capture::Capture>(capture));
  driver.start();
  ASSERT_EQ(driver.channels().size(), 1u);
  std::vector<double> value(1);
  const double expected_t[] = {0.0, 0.002, 0.004, 0.006, 0.008, 0.010, 0.012};
  for (int i = 0; i < 7; ++i) {
    ASSERT_EQ(driver.read({}, value), io::ReadStatus::ok);
    EXPECT_NEAR(*driver.source_time(), expected_t[i], 1e-12);
    EXPECT_EQ(value[0], capture.values[2][static_cast<std::size_t>(i % 3)]);
  }
  settings.channels = {"p9"};
  EXPECT_THROW(io::ReplayDriver(settings, std::make_shared<const capture::Capture>(capture)),
               io::DriverError);
}

TEST(CaptureRecorder, RotatesAndReplaysToTheSameSamples) {
  const std::string dir = test::scratch_dir("capture_recorder_roundtrip");
  pipeline::RecordingConfig recording;
  recording.directory = dir;
  recording.rotate_seconds = 1.0;
  recording.keep_files = 0;
  std::vector<realtime::Sample> written;
  std::vector<std::string> files;
  {
    pipeline::CaptureRecorder recorder("main", {"p1", "u"}, 500.0, recording);
    for (int i = 0; i < 1200; ++i) {
      realtime::Sample s;
      s.tick = static_cast<std::uint64_t>(i);
      s.t = i * 0.002;
      s.channel_count = 2;
      s.values[0] = 8.6e6 + std::sin(i * 0.37) * 1.234567e4;
      s.values[1] = (i % 97 == 0) ? NAN : std::cos(i * 0.11) / 3.0;  // gaps round-trip too
      recorder.record(s);
      written.push_back(s);
    }
    files = recorder.files();
  }
  ASSERT_EQ(files.size(), 3u) << "2.4 s at 1 s per file";
  std::size_t row = 0;
  for (const auto& file : files) {
    io::ReplaySettings settings;
    settings.path = file;
    io::ReplayDriver driver(settings);
    driver.start();
    std::vector<double> values(2);
    while (driver.read({}, values) == io::ReadStatus::ok) {
      ASSERT_LT(row, written.size());
      EXPECT_EQ(*driver.source_time(), written[row].t);
      EXPECT_EQ(values[0], written[row].values[0]);
      if (std::isnan(written[row].values[1])) {
        EXPECT_TRUE(std::isnan(values[1]));
      } else {
        EXPECT_EQ(values[1], written[row].values[1]);
      }
      ++row;
    }
  }
  EXPECT_EQ(row, written.size());
}

TEST(CaptureRecorder, KeepsOnlyTheNewestFiles) {
  const std::string dir = test::scratch_dir("capture_recorder_keep");
  pipeline::RecordingConfig recording;
  recording.directory = dir;
  recording.rotate_seconds = 1.0;
  recording.keep_files = 2;
  pipeline::CaptureRecorder recorder("g", {"p1"}, 500.0, recording);
  realtime::Sample s;
  s.channel_count = 1;
  for (int i = 0; i < 5; ++i) {
    s.t = i * 1.0;
    recorder.record(s);
  }
  recorder.flush();
  std::size_t on_disk = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++on_disk;
  EXPECT_EQ(on_disk, 2u);
  EXPECT_EQ(recorder.files().size(), 2u);
}

}  // namespace
}  // namespace leakmon
