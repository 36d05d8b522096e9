// What the daemon keeps across restarts (pipeline/state_store.hpp): the store's files, and replay
// with a state directory acting as one daemon stopped and started between two captures.
#include "pipeline/state_store.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "detect/factory.hpp"
#include "pipeline/replay.hpp"
#include "sim/scenario.hpp"
#include "sim/simulate.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::pipeline {
namespace {

using capture::Role;

namespace fs = std::filesystem;

ActuatorConfig actuator(const std::string& name) {
  ActuatorConfig a;
  a.name = name;
  a.channels[Role::p1] = {"rig", "p1", std::nullopt};
  a.channels[Role::p2] = {"rig", "p2", std::nullopt};
  a.channels[Role::u] = {"rig", "u", std::nullopt};
  a.channels[Role::x] = {"rig", "x", std::nullopt};
  return a;
}

ActuatorState sample_state(const std::string& name) {
  ActuatorState s;
  s.actuator = name;
  s.fingerprint = state_fingerprint(actuator(name), 2'000'000);
  s.saved_unix = 1763890000.125;
  s.alarm = AlarmState::returned_unacknowledged;
  s.alarm_condition = false;
  s.detector = detect::DetectorState("flow_balance", 1);
  s.detector.put("cusum", 1.0 / 3.0);
  const double list[] = {0.1, -2.5e-13, std::numeric_limits<double>::quiet_NaN()};
  s.detector.put("learned", list);
  return s;
}

std::string fresh_dir(const std::string& name) {
  const std::string dir = test::scratch_dir(name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

void write(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

TEST(StateStore, RoundTripIsExact) {
  const StateStore store(fresh_dir("StateRoundTrip"));
  const ActuatorState saved = sample_state("ram 1");
  store.save(saved);
  const auto loaded = store.load("ram 1", saved.fingerprint);
  ASSERT_TRUE(loaded.state) << loaded.warning;
  EXPECT_TRUE(loaded.warning.empty());
  EXPECT_EQ(loaded.state->actuator, "ram 1");
  EXPECT_EQ(loaded.state->saved_unix, saved.saved_unix);
  EXPECT_EQ(loaded.state->alarm, AlarmState::returned_unacknowledged);
  EXPECT_TRUE(loaded.state->detector == saved.detector);
  EXPECT_EQ(loaded.state->fingerprint.parts, saved.fingerprint.parts);
  EXPECT_EQ(encode_state(*loaded.state), encode_state(saved));
  // No file yet: a first start, not a warning.
  const auto none = store.load("other", saved.fingerprint);
  EXPECT_FALSE(none.state);
  EXPECT_TRUE(none.warning.empty());
}

TEST(StateStore, InterruptedWriteLeavesTheOldFileWhole) {
  const std::string dir = fresh_dir("StateInterrupted");
  const StateStore store(dir);
  const ActuatorState old_state = sample_state("ram");
  store.save(old_state);
  const std::string before = read(store.file_of("ram"));
  // A crash mid-write of another process leaves its temporary file behind: ignored.
  write(store.file_of("ram").string() + ".tmp.999999", before.substr(0, before.size() / 2));
  // This process's write fails (its temporary path is taken by a directory).
  fs::create_directories(store.file_of("ram").string() + ".tmp." + std::to_string(::getpid()));
  ActuatorState newer = old_state;
  newer.detector.put("cusum", 9.0);
  EXPECT_THROW(store.save(newer), std::runtime_error);
  EXPECT_EQ(read(store.file_of("ram")), before);
  const auto loaded = store.load("ram", old_state.fingerprint);
  ASSERT_TRUE(loaded.state) << loaded.warning;
  EXPECT_EQ(loaded.state->detector.get("cusum"), 1.0 / 3.0);
  EXPECT_TRUE(store.remove("ram"));
  EXPECT_FALSE(fs::exists(store.file_of("ram").string() + ".tmp.999999"));
}

TEST(StateStore, DamagedNewerOrChangedFilesAreSetAsideWithAWarning) {
  const StateStore store(fresh_dir("StateDamaged"));
  const ActuatorState saved = sample_state("ram");
  store.save(saved);
  const std::string good = read(store.file_of("ram"));
  auto warning_for = [&](const std::string& text, const StateFingerprint& expected) {
    write(store.file_of("ram"), text);
    const auto loaded = store.load("ram", expected);
    EXPECT_FALSE(loaded.state);
    return loaded.warning;
  };
  std::string corrupt = good;
  corrupt[corrupt.find("cusum") + 7] ^= 0x01;
  EXPECT_NE(warning_for(corrupt, saved.fingerprint).find("corrupt"), std::string::npos);
  EXPECT_NE(warning_for(good.substr(0, good.size() / 2), saved.fingerprint).find("truncated"),
            std::string::npos);
  EXPECT_NE(warning_for(good.substr(0, good.size() - 1), saved.fingerprint).find("truncated"),
            std::string::npos);
  EXPECT_FALSE(warning_for("", saved.fingerprint).empty());
  EXPECT_FALSE(warning_for("\x7f"
                           "ELF garbage\n",
                           saved.fingerprint)
                   .empty());
  std::string newer = good;
  newer.replace(0, newer.find('\n'), "leakmon-state " + std::to_string(kStateFormatVersion + 1));
  EXPECT_NE(warning_for(newer, saved.fingerprint).find("newer"), std::string::npos);
  ActuatorConfig changed = actuator("ram");
  changed.features.window = 512;
  const std::string warning = warning_for(good, state_fingerprint(changed, 2'000'000));
  EXPECT_NE(warning.find("configuration changed"), std::string::npos) << warning;
  EXPECT_NE(warning.find("window=512"), std::string::npos) << warning;
  // Each part of the fingerprint matters.
  const auto base = state_fingerprint(actuator("ram"), 2'000'000);
  // The channels part as every saved state has it (its hash decides whether the state loads).
  ASSERT_FALSE(base.parts.empty());
  EXPECT_EQ(base.parts[0].first, "channels");
  EXPECT_EQ(base.parts[0].second, "p1=p1 p2=p2 u=u x=x xref= ps= temp=");
  ActuatorConfig other_channel = actuator("ram");
  other_channel.channels[Role::p2].channel = "p2b";
  ActuatorConfig other_detector = actuator("ram");
  other_detector.detector = "index_cusum";
  ActuatorConfig other_wavelet = actuator("ram");
  other_wavelet.features.wavelet = "db4";
  for (const auto& a : {other_channel, other_detector, other_wavelet}) {
    EXPECT_FALSE(state_fingerprint(a, 2'000'000) == base);
  }
  EXPECT_FALSE(state_fingerprint(actuator("ram"), 1'000'000) == base);
  // Driver names do not: a state learned from a capture fits the daemon.
  ActuatorConfig other_driver = actuator("ram");
  other_driver.channels[Role::p1].driver = other_driver.channels[Role::p2].driver = "capture";
  EXPECT_TRUE(state_fingerprint(other_driver, 2'000'000) == base);
}

TEST(StateStore, EachActuatorHasItsOwnFingerprint) {
  const StateStore store(fresh_dir("StatePerActuator"));
  store.save(sample_state("left"));
  store.save(sample_state("right"));
  ActuatorConfig changed = actuator("left");
  changed.detector = "fused";
  EXPECT_FALSE(store.load("left", state_fingerprint(changed, 2'000'000)).state);
  const auto right = store.load("right", state_fingerprint(actuator("right"), 2'000'000));
  ASSERT_TRUE(right.state) << right.warning;
  EXPECT_EQ(store.list().states.size(), 2u);
}

// Replay with --state-dir: two captures of the same rig, the second with a leak open from its
// start (it opened while the daemon was down).
capture::Capture capture_of(std::uint64_t seed, double duration, double leak) {
  sim::Scenario scenario = sim::preset("healthy", seed);
  scenario.duration_s = duration;
  scenario.effects.internal_leakage.reset();
  if (leak > 0.0) {
    sim::InternalLeakage effect;
    effect.C_L = leak;
    effect.onset_s = 0.0;
    scenario.effects.internal_leakage = effect;
  }
  return sim::simulate(scenario);
}

std::vector<io::Event> of_kind(const ReplayResult& result, io::EventKind kind) {
  std::vector<io::Event> out;
  std::copy_if(result.events.begin(), result.events.end(), std::back_inserter(out),
               [&](const io::Event& e) { return e.kind == kind; });
  return out;
}

TEST(ReplayStateDir, ALeakOpenedWhileDownIsFoundOnlyWhenTheStateWasKept) {
  const std::string dir = fresh_dir("ReplayStateDir");
  const capture::Capture first = capture_of(21, 130.0, 0.0);
  const capture::Capture leaking = capture_of(22, 120.0, 2e-12);
  const capture::Capture healthy = capture_of(23, 120.0, 0.0);
  const DaemonConfig config = default_replay_config(first);
  ReplayOptions keep;
  keep.state_directory = dir;

  const ReplayResult learned = replay_capture(first, config, keep);
  EXPECT_TRUE(of_kind(learned, io::EventKind::alarm_raised).empty());
  ASSERT_FALSE(learned.actuators.front().learning) << "130 s should be enough to learn";
  EXPECT_TRUE(fs::exists(StateStore(dir).file_of("actuator")));
  const std::string saved = read(StateStore(dir).file_of("actuator"));

  // Restart into the leak with the state: found within 60 s of the start.
  const ReplayResult resumed = replay_capture(leaking, config, keep);
  ASSERT_EQ(of_kind(resumed, io::EventKind::state_restored).size(), 1u);
  const auto raised = of_kind(resumed, io::EventKind::alarm_raised);
  ASSERT_FALSE(raised.empty()) << "the leak that opened while down was not found";
  EXPECT_LT(raised.front().t - leaking.column("t").front(), 60.0);
  std::printf("with the state: internal_leakage %.1f s after the restart\n",
              raised.front().t - leaking.column("t").front());

  // Without it (the old behaviour), the second capture learns the leak as healthy.
  const ReplayResult relearned = replay_capture(leaking, config, {});
  EXPECT_TRUE(of_kind(relearned, io::EventKind::alarm_raised).empty())
      << "expected the leak to be learned as healthy without the state";
  std::printf("without the state: %zu alarm(s)\n",
              of_kind(relearned, io::EventKind::alarm_raised).size());

  // A healthy restart raises nothing.
  write(StateStore(dir).file_of("actuator"), saved);
  const ReplayResult healthy_restart = replay_capture(healthy, config, keep);
  EXPECT_EQ(of_kind(healthy_restart, io::EventKind::state_restored).size(), 1u);
  EXPECT_TRUE(of_kind(healthy_restart, io::EventKind::alarm_raised).empty());
  EXPECT_FALSE(healthy_restart.actuators.front().learning);

  // A corrupt file: one warning event, and a fresh learning phase.
  write(StateStore(dir).file_of("actuator"), saved.substr(0, saved.size() / 3));
  const ReplayResult fresh = replay_capture(leaking, config, keep);
  const auto discarded = of_kind(fresh, io::EventKind::state_discarded);
  ASSERT_EQ(discarded.size(), 1u);
  EXPECT_NE(discarded.front().message.find("truncated"), std::string::npos);
  EXPECT_TRUE(of_kind(fresh, io::EventKind::state_restored).empty());
}

// Upgrading from a build whose default with u and x was flow_balance: the state that build saved
// for a `default` actuator is set aside with one event that names the change, and the actuator
// learns again (flow_law); nothing is read into the other detector.
TEST(ReplayStateDir, TheOldDefaultsFlowBalanceStateIsSetAsideAndLearnedAgain) {
  const std::string dir = fresh_dir("ReplayStateDirUpgrade");
  const capture::Capture first = capture_of(31, 110.0, 0.0);
  const capture::Capture next = capture_of(32, 110.0, 0.0);
  DaemonConfig old_default = default_replay_config(first);
  ASSERT_EQ(old_default.actuators.size(), 1u);
  old_default.actuators.front().detector = "flow_balance";  // what `default` was
  ReplayOptions keep;
  keep.state_directory = dir;
  const ReplayResult learned = replay_capture(first, old_default, keep);
  ASSERT_FALSE(learned.actuators.front().learning);
  ASSERT_NE(read(StateStore(dir).file_of("actuator")).find("flow_balance"), std::string::npos);

  const ReplayResult upgraded = replay_capture(next, default_replay_config(next), keep);
  const auto discarded = of_kind(upgraded, io::EventKind::state_discarded);
  ASSERT_EQ(discarded.size(), 1u);
  EXPECT_NE(discarded.front().message.find("detector: 'flow_balance' -> 'flow_law'"),
            std::string::npos)
      << discarded.front().message;
  EXPECT_NE(discarded.front().message.find("learning afresh"), std::string::npos);
  EXPECT_TRUE(of_kind(upgraded, io::EventKind::state_restored).empty());
  EXPECT_EQ(upgraded.actuators.front().detector, "flow_law");
  EXPECT_TRUE(of_kind(upgraded, io::EventKind::alarm_raised).empty());

  EXPECT_NE(read(StateStore(dir).file_of("actuator")).find("flow_law"), std::string::npos);

  // Whatever the fingerprint says, flow_law refuses a flow_balance state rather than misread it.
  const auto law = detect::make_detector("default", {true, true, true, true}, 0.04, nullptr);
  EXPECT_THROW(law->import_state(detect::DetectorState("flow_balance", 4)), detect::StateError);
}

}  // namespace
}  // namespace leakmon::pipeline

namespace leakmon::pipeline {
namespace {

// The rig sizes what the detector learns, so a changed `rig:` relearns like a changed option;
// the paper's rig (nothing stated) keeps the fingerprint it had before `rig:` existed.
TEST(StateStore, TheRigIsPartOfTheFingerprintWhenItStatesSomething) {
  const auto base = state_fingerprint(actuator("ram"), 2'000'000);
  for (const auto& [name, value] : base.parts) EXPECT_NE(name, "rig");
  ActuatorConfig empty_rig = actuator("ram");
  empty_rig.rig = sim::read_rig(config::ConfigNode::load_string("{}", "rig.yaml"));
  EXPECT_TRUE(state_fingerprint(empty_rig, 2'000'000) == base);

  ActuatorConfig described = actuator("ram");
  described.rig =
      sim::read_rig(config::ConfigNode::load_string("{supply_pressure: 21.0e6}", "rig.yaml"));
  const auto with_rig = state_fingerprint(described, 2'000'000);
  EXPECT_FALSE(with_rig == base);
  const auto rig_part = std::find_if(with_rig.parts.begin(), with_rig.parts.end(),
                                     [](const auto& part) { return part.first == "rig"; });
  ASSERT_NE(rig_part, with_rig.parts.end());
  EXPECT_EQ(rig_part->second, "supply_pressure=21000000");
  ActuatorConfig resupplied = described;
  resupplied.rig =
      sim::read_rig(config::ConfigNode::load_string("{supply_pressure: 21.5e6}", "rig.yaml"));
  EXPECT_FALSE(state_fingerprint(resupplied, 2'000'000) == with_rig);

  // Saved on one rig, loaded on another: set aside, naming what changed.
  const StateStore store(fresh_dir("StateRigChanged"));
  ActuatorState saved = sample_state("ram");
  saved.fingerprint = with_rig;
  store.save(saved);
  const auto loaded = store.load("ram", state_fingerprint(resupplied, 2'000'000));
  EXPECT_FALSE(loaded.state);
  EXPECT_NE(loaded.warning.find("supply_pressure=21500000"), std::string::npos) << loaded.warning;
  EXPECT_TRUE(store.load("ram", with_rig).state);
}

}  // namespace
}  // namespace leakmon::pipeline
