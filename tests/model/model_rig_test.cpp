// Issue 24's building blocks that need no fitting: the rig check of the stated values the
// signals can check (supply from the chamber levels, load stiffness from the force balance),
// effect sizes and calibration bounds relative to the rig, the change point of an effect that
// starts inside a capture, and where `leakmon model check` takes the rig from (errors at
// file:line:column). Random draws take a fresh seed each run (printed; LEAKMON_TEST_SEED
// forces one).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "config/yaml_reader.hpp"
#include "model/calibration_fit.hpp"
#include "model/change_point.hpp"
#include "model/diagnosis.hpp"
#include "model/effect_library.hpp"
#include "model/rig_check.hpp"
#include "model/rig_source.hpp"
#include "model/synthetic_case.hpp"
#include "sim/rig_draw.hpp"
#include "tests/model/test_seed.hpp"
#include "tests/support/paths.hpp"

namespace leakmon::model {
namespace {

CaseSettings other_rig(double seconds, const std::string& misstate = "") {
  CaseSettings s;
  s.duration_s = seconds;
  s.other_rig = true;
  s.misstate = misstate;
  return s;
}

RigCheck check(const SyntheticCase& c) {
  const MeasuredRecord record = measured_record(simulate_case(c));
  return check_rig(record, split_record(record).fitting, c.told.params);
}

std::string findings(const RigCheck& r) {
  std::string out;
  for (const auto& f : r.findings) {
    out += f.parameter + " " + std::to_string(f.stated) + " -> " + std::to_string(f.fitted) + "; ";
  }
  return out.empty() ? "none" : out;
}

// A rig told its true description (its beta, Kv, m, b off by up to MODEL.md's calibratable
// ranges, as on any real rig): nothing to contradict.
TEST(RigCheck, TheTrueDescriptionIsNotContradicted) {
  const auto seed = test::model_test_seed("RigCheck.TheTrueDescriptionIsNotContradicted");
  for (std::uint64_t i = 0; i < 2; ++i) {
    const SyntheticCase c = draw_case(seed + i, "none", other_rig(30.0));
    const RigCheck r = check(c);
    std::printf("%s\n  levels %.4g / %.4g MPa, K_s %.4g +- %.2g kN/m: %s\n",
                sim::describe(c.told).c_str(), r.sum_rest * 1e-6, r.sum_open * 1e-6,
                r.balance.K_s * 1e-3, r.balance.K_s_error * 1e-3, findings(r).c_str());
    EXPECT_TRUE(r.findings.empty()) << "seed " << seed + i << ": " << findings(r);
  }
}

// A supply stated 15-30 % off (either way): found from the chamber levels, within 2 % (the
// levels give ps + pt to a few kPa), and nothing else contradicted.
TEST(RigCheck, FindsAMisstatedSupply) {
  const auto seed = test::model_test_seed("RigCheck.FindsAMisstatedSupply");
  const SyntheticCase c = draw_case(seed, "none", other_rig(30.0, "supply_pressure"));
  const RigCheck r = check(c);
  std::printf("supply true %.4g told %.4g: %s\n", c.misstated_true, c.misstated_stated,
              findings(r).c_str());
  ASSERT_EQ(r.findings.size(), 1u) << findings(r);
  EXPECT_EQ(r.findings[0].parameter, "supply_pressure");
  EXPECT_EQ(r.findings[0].stated, c.misstated_stated);
  EXPECT_NEAR(r.findings[0].fitted, c.misstated_true, 0.02 * c.misstated_true);
  EXPECT_EQ(r.assumed.ps, r.findings[0].fitted);
}

// A load stiffness stated 40-80 % off: found from the force balance, within 2 %, soft springs
// included (a 22.4 kN/m spring stated 12.7 went unsaid under the old 1 % floor). A rig whose
// pressures ring past the transducers' range end every few tens of milliseconds (a 468 kg
// mass on a 538 kN/m spring) leaves no whole segment: the model check refuses its capture
// and names the range end, and the next draw is judged (3 of 600 draws did so).
TEST(RigCheck, FindsAMisstatedLoadStiffness) {
  const auto first = test::model_test_seed("RigCheck.FindsAMisstatedLoadStiffness");
  for (std::uint64_t seed = first; seed < first + 4; ++seed) {
    const SyntheticCase c = draw_case(seed, "none", other_rig(30.0, "load_stiffness"));
    const MeasuredRecord record = measured_record(simulate_case(c));
    const SegmentPlan plan = split_record(record);
    if (plan.fitting.size() < 4 || plan.held_out.size() < 4) {
      try {
        diagnose(record, c.told);
        ADD_FAILURE() << "seed " << seed << ": a capture without 4 whole segments was checked";
      } catch (const ModelCheckError& e) {
        std::printf("seed %llu refused: %s\n", static_cast<unsigned long long>(seed), e.what());
        EXPECT_NE(std::string(e.what()).find("range end"), std::string::npos) << e.what();
      }
      continue;
    }
    const RigCheck r = check_rig(record, plan.fitting, c.told.params);
    std::printf("%s\nload stiffness true %.4g told %.4g; the balance's %.4g +- %.2g: %s\n",
                sim::describe(c.told).c_str(), c.misstated_true, c.misstated_stated, r.balance.K_s,
                r.balance.K_s_error, findings(r).c_str());
    ASSERT_EQ(r.findings.size(), 1u) << "seed " << seed << ": " << findings(r);
    EXPECT_EQ(r.findings[0].parameter, "load_stiffness");
    EXPECT_NEAR(r.findings[0].fitted, c.misstated_true, 0.02 * c.misstated_true);
    EXPECT_EQ(r.assumed.K_s, r.findings[0].fitted);
    return;
  }
  FAIL() << "four draws in a row from seed " << first << " gave no capture to check";
}

// The refusal above, on the draw that found it (seed 13451785284935577263: 468 kg on 538 kN/m,
// a 48 mm bore at 22.9 MPa whose chambers ring past a 35 MPa transducer's range end every
// 40-120 ms): the message names the channels, their range end and where it starts, not gaps.
TEST(RigCheck, ARigRingingPastItsTransducersRangeIsRefusedNamingTheRangeEnd) {
  const SyntheticCase c =
      draw_case(13451785284935577263ull, "none", other_rig(30.0, "load_stiffness"));
  const MeasuredRecord record = measured_record(simulate_case(c));
  try {
    diagnose(record, c.told);
    FAIL() << "checked a capture with " << split_record(record).fitting.size()
           << " whole fitting segments";
  } catch (const ModelCheckError& e) {
    const std::string message = e.what();
    std::printf("%s\n", message.c_str());
    EXPECT_NE(message.find("only 0 fitting"), std::string::npos);
    EXPECT_NE(message.find("p1 at its range end (34.99 MPa)"), std::string::npos);
    EXPECT_NE(message.find("p2 at its range end"), std::string::npos);
    EXPECT_NE(message.find("from row "), std::string::npos);
  }
}

// The library's effects that move the chamber levels are not a mis-stated supply: an
// external leak lowers them most at rest (unevenly), a transducer offset shifts p1 + p2 and
// the force balance alike. Both at their range's top on the paper's rig, and an offset of
// 3e5 Pa on a 7 MPa rig (4.3 % of the supply), which the levels alone would not tell apart.
TEST(RigCheck, AnExternalLeakOrATransducerOffsetIsNoSupply) {
  const auto seed = test::model_test_seed("RigCheck.AnExternalLeakOrATransducerOffsetIsNoSupply");
  CaseSettings paper;
  paper.duration_s = 30.0;
  SyntheticCase leak = draw_case(seed, "external_leakage", paper);
  leak.scenario.effects.external_leakage->C_E = 2e-12;
  EXPECT_TRUE(check(leak).findings.empty()) << findings(check(leak));

  SyntheticCase offset = draw_case(seed + 1, "sensor_offset", paper);
  offset.scenario.params.ps = 7e6;
  offset.told.params.ps = 7e6;
  offset.scenario.sensors = sim::sensors_for(offset.scenario.params);
  offset.scenario.reference.amp_max = sim::max_step_amplitude(offset.scenario.params);
  offset.scenario.reference.amp_min = offset.scenario.reference.amp_max / 2.0;
  offset.scenario.effects.sensor_offset->offset = 3e5;
  const RigCheck r = check(offset);
  std::printf("offset 3e5 on %s at 7 MPa: levels %.4g MPa, constant force %.4g N\n",
              sim::to_string(offset.scenario.effects.sensor_offset->channel).data(),
              r.sum_rest * 1e-6, r.balance.constant);
  EXPECT_TRUE(r.findings.empty()) << findings(r);
}

// The capture's own `ps` column, where the rig records it, is the supply.
TEST(RigCheck, ReadsTheSupplyColumnWhenThereIsOne) {
  const auto seed = test::model_test_seed("RigCheck.ReadsTheSupplyColumnWhenThereIsOne");
  CaseSettings paper;
  paper.duration_s = 24.0;
  SyntheticCase c = draw_case(seed, "none", paper);
  c.scenario.record.ps = true;
  c.told.params.ps = 14e6;
  const RigCheck r = check(c);
  EXPECT_TRUE(r.supply_column);
  ASSERT_EQ(r.findings.size(), 1u) << findings(r);
  EXPECT_NEAR(r.findings[0].fitted, 17.2e6, 0.01 * 17.2e6);
}

// On the paper's rig every effect candidate is exactly as before; on another one the sizes
// that scale with the rig follow it (a leak with the valve, friction with the force), and a
// spool_lag is a spool slower than the rig's own.
// `model evaluate --programs`: a random test program replaces the steps, on the rig and with
// the effects the same seed draws without one (its own stream), every phase within the capture,
// and one the rig runs (sim::check_viability: it tracks, does not saturate or hit a stop).
TEST(ProgramCases, AProgramReplacesTheStepsOnTheSameRigWithTheSameEffects) {
  const auto first =
      test::model_test_seed("ProgramCases.AProgramReplacesTheStepsOnTheSameRigWithTheSameEffects");
  for (std::uint64_t i = 0; i < 3; ++i) {
    CaseSettings steps = other_rig(60.0);
    steps.onset = true;
    CaseSettings programs = steps;
    programs.program = true;
    const SyntheticCase a = draw_case(first + i, "internal_leakage", steps);
    const SyntheticCase b = draw_case(first + i, "internal_leakage", programs);
    EXPECT_TRUE(a.scenario.program.empty());
    EXPECT_EQ(a.scenario.params.D, b.scenario.params.D);
    EXPECT_EQ(a.scenario.params.m, b.scenario.params.m);
    EXPECT_EQ(a.scenario.params.K_s, b.scenario.params.K_s);
    EXPECT_EQ(a.main_value, b.main_value);
    EXPECT_EQ(a.onset_s, b.onset_s);
    const auto& program = b.scenario.program;
    ASSERT_GE(program.size(), 3u);
    ASSERT_LE(program.size(), 8u);
    double total = 0.0;
    for (const auto& phase : program) {
      total += phase.duration_s;
      EXPECT_LE(std::abs(phase.A), 0.045 * b.scenario.reference.amp_max / 0.05 + 1e-12);
      EXPECT_LE(std::abs(phase.X), b.scenario.reference.amp_max + 1e-12);
    }
    EXPECT_NEAR(total, 60.0, 1e-9);
    // A program is drawn again while the rig cannot run it; a rig that was drawn on 12 s of
    // steps may still ring over the whole capture (3 of 600 draws), and then no program helps.
    const sim::Viability steps_run = sim::check_viability(a.scenario, 60.0);
    const sim::Viability runs = sim::check_viability(b.scenario, 60.0);
    EXPECT_TRUE(runs.ok || !steps_run.ok) << "seed " << first + i << ": " << runs.reason;
  }
}

TEST(EffectLibrary, SizesFollowTheRig) {
  const auto paper = effect_library(0.0, false, 0.002);
  const auto same = effect_library(0.0, false, 0.002, sim::Parameters{});
  ASSERT_EQ(paper.size(), same.size());
  sim::Parameters big;
  big.Kv *= 4.0;
  big.D = 0.08;
  big.d = 0.04;
  big.tau = 0.01;
  const auto other = effect_library(0.0, false, 0.002, big);
  const RigScales k = RigScales::of(big);
  EXPECT_EQ(RigScales::of(sim::Parameters{}).leak, 1.0);
  EXPECT_DOUBLE_EQ(k.leak, 4.0);
  EXPECT_GT(k.force, 4.0);
  for (std::size_t i = 0; i < paper.size(); ++i) {
    EXPECT_EQ(paper[i].parameters.front().scale, same[i].parameters.front().scale);
    if (paper[i].effect == "internal_leakage") {
      EXPECT_DOUBLE_EQ(other[i].parameters.front().scale, 4.0 * paper[i].parameters.front().scale);
      EXPECT_FALSE(other[i].plausible({1.5e-13}));  // a paper-sized small leak: too small here
      EXPECT_TRUE(paper[i].plausible({1.5e-13}));
    }
    if (paper[i].effect == "spool_lag") {
      EXPECT_TRUE(paper[i].plausible({0.006}));
      EXPECT_FALSE(other[i].plausible({0.012}));  // slower than 2.5 ms, not than 10 ms
      EXPECT_TRUE(other[i].plausible({0.03}));
    }
  }
}

// The calibration's bounds are twice MODEL.md's ranges around the stated values.
TEST(Calibration, BoundsAreAroundTheStatedValues) {
  const Calibration stated{1.2e9, 1e-6, 120.0, 2000.0};
  const auto [lower, upper] = calibration_bounds(stated);
  EXPECT_NEAR(lower.beta, 0.5 * 1.2e9, 1.0);
  EXPECT_NEAR(upper.Kv, 1.2e-6, 1e-15);
  EXPECT_NEAR(lower.m, 0.6 * 120.0, 1e-9);
  EXPECT_NEAR(upper.b, 1.6 * 2000.0, 1e-9);
  EXPECT_TRUE(calibration_at_bound(stated, stated).empty());
  EXPECT_EQ(calibration_at_bound({1.2e9, 1e-6, 0.6 * 120.0, 2000.0}, stated),
            std::vector<std::string>{"m"});
  // The paper's values on a rig stated five times heavier: m on its bound.
  EXPECT_EQ(calibration_at_bound({1.2e9, 1e-6, 24.0, 2000.0}, stated),
            std::vector<std::string>{"m"});
}

// A step in the segments' log errors is found where it is; a capture whose errors only
// follow the operating point (no step) gives a small statistic. Rates measured on 2000 draws
// of this test's numbers (numpy): the flat statistic exceeded the diagnosis's bar of 5 in 1,
// the stepped one stayed above 10.1 and within 14 segments (7 s) of the step in all but 1 (the
// diagnosis refines the onset with the fitted model afterwards).
TEST(ChangePoint, FindsWhereTheErrorStepsUp) {
  const auto seed = test::model_test_seed("ChangePoint.FindsWhereTheErrorStepsUp");
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  MeasuredRecord record;
  record.dt = 0.002;
  const std::size_t segments = 240, length = 250;
  for (std::size_t k = 0; k < segments * length; ++k) record.t.push_back(k * record.dt);
  std::vector<Segment> all;
  for (std::size_t i = 0; i < segments; ++i) all.push_back({i * length, length});
  std::vector<double> flat, stepped;
  for (std::size_t i = 0; i < segments; ++i) {
    const double operating_point = 1.5 * normal(random);  // log errors vary a lot per segment
    flat.push_back(operating_point);
    stepped.push_back(operating_point + (i >= 170 ? 3.0 : 0.0));
  }
  const auto none = find_change_point(record, all, flat);
  const auto step = find_change_point(record, all, stepped);
  ASSERT_TRUE(none && step);
  std::printf("flat: t %.2f s statistic %.2f; stepped: t %.2f s statistic %.2f\n", none->t_s,
              none->statistic, step->t_s, step->statistic);
  EXPECT_LT(none->statistic, DiagnosisSettings{}.min_change_statistic);
  EXPECT_GT(step->statistic, 8.0);
  EXPECT_NEAR(step->t_s, 170 * 0.5, 7.0);
}

// Under a test program the error follows the phases: a hold's is the transducers' noise, a
// sine's grows with its speed, a sweep's with its frequency. The plain split lands at such a
// phase change; with the segments' excitation (segment_excitation, from x) regressed out it
// lands at an onset inside a phase, and a program without one gives a much smaller statistic.
// Measured on 300 seeds of this test: the plain split never within 10 s of the onset; the
// stepped statistic 18.1 or more, within 0.5 s of the onset in all; without the step 7.3 at
// most, above the diagnosis's bar of 5 in 19 (the hold's noise floor bends the error's law,
// which log-linear regressors follow only roughly: the onsets tried are judged on held-out
// data, and the bar here is the margin to a real step).
TEST(ChangePoint, FindsAnOnsetInsideAPhaseBeyondTheProgramsExcitation) {
  const auto seed =
      test::model_test_seed("ChangePoint.FindsAnOnsetInsideAPhaseBeyondTheProgramsExcitation");
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  MeasuredRecord record;
  record.dt = 0.002;
  const std::size_t segments = 240, length = 250;
  // A hold (segments 0-79), a 1 Hz sine of 10 mm (80-199), a sweep from 1 to 3 Hz (200-239).
  const double two_pi = 2.0 * std::acos(-1.0);
  double phase = 0.0;
  std::vector<double> speed(segments, 0.0);  // rms velocity of each segment [m/s]
  for (std::size_t k = 0; k < segments * length; ++k) {
    const std::size_t i = k / length;
    record.t.push_back(static_cast<double>(k) * record.dt);
    double frequency = 0.0;
    if (i >= 200) {
      frequency = 1.0 + 2.0 * static_cast<double>(k - 200 * length) / (40.0 * length);
    } else if (i >= 80) {
      frequency = 1.0;
    }
    phase += two_pi * frequency * record.dt;
    record.x.push_back((frequency > 0.0 ? 0.01 * std::sin(phase) : 0.0) + 1e-5 * normal(random));
    speed[i] = 0.01 * two_pi * frequency / std::sqrt(2.0);
  }
  std::vector<Segment> all;
  for (std::size_t i = 0; i < segments; ++i) all.push_back({i * length, length});
  const auto excitation = segment_excitation(record, all);
  std::vector<double> flat, stepped;
  for (std::size_t i = 0; i < segments; ++i) {
    // The model's error: the noise's, plus a share of the motion it does not follow.
    const double error = std::log(1e-8 + std::pow(0.01 * speed[i], 2)) + 0.2 * normal(random);
    flat.push_back(error);
    stepped.push_back(error + (i >= 140 ? 0.8 : 0.0));
  }
  const auto plain = find_change_point(record, all, stepped);
  const auto none = find_change_point_beyond_excitation(record, all, flat, excitation);
  const auto step = find_change_point_beyond_excitation(record, all, stepped, excitation);
  ASSERT_TRUE(plain && none && step);
  std::printf(
      "plain: t %.2f s statistic %.2f; beyond the excitation: none t %.2f s statistic "
      "%.2f, stepped t %.2f s statistic %.2f\n",
      plain->t_s, plain->statistic, none->t_s, none->statistic, step->t_s, step->statistic);
  EXPECT_GT(std::abs(plain->t_s - 140 * 0.5), 10.0) << "the plain split found the onset";
  EXPECT_LT(none->statistic, 0.5 * step->statistic);
  EXPECT_LT(none->statistic, 10.0);
  EXPECT_GT(step->statistic, 12.0);
  EXPECT_NEAR(step->t_s, 140 * 0.5, 2.0);
  EXPECT_NEAR(step->step, 0.8, 0.2);
}

std::string write(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// `--config C.yaml --actuator NAME`: that actuator's rig:, the paper's rig for an actuator
// without one, and errors at file:line:column.
TEST(RigSource, TakesTheActuatorsRigFromTheDaemonConfiguration) {
  const std::string dir = test::scratch_dir("model_rig_source");
  const std::string config = write(dir + "/leakmon.yaml",
                                   "drivers: []\n"
                                   "actuators:\n"
                                   "  - name: press\n"
                                   "    rig:\n"
                                   "      supply_pressure: 21.0e6\n"
                                   "      load_stiffness: 60.0e3\n"
                                   "  - name: paper\n");
  const auto press = load_actuator_rig(config, "press");
  EXPECT_EQ(press.params.ps, 21e6);
  EXPECT_EQ(press.params.K_s, 60e3);
  EXPECT_TRUE(load_actuator_rig(config, "paper").nominal());
  try {
    load_actuator_rig(config, "crane");
    FAIL() << "an unknown actuator was accepted";
  } catch (const config::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(config + ":3:"), std::string::npos) << what;  // the actuators list
    EXPECT_NE(what.find("crane"), std::string::npos) << what;
    EXPECT_NE(what.find("press, paper"), std::string::npos) << what;
  }
  const std::string bad = write(dir + "/bad.yaml",
                                "actuators:\n"
                                "  - name: press\n"
                                "    rig: {supply_pressure: 21.0e6, bore_diameter: 0.05}\n");
  try {
    load_actuator_rig(bad, "press");
    FAIL() << "an unknown rig key was accepted";
  } catch (const config::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(bad + ":3:"), std::string::npos) << what;
    EXPECT_NE(what.find("bore_diameter"), std::string::npos) << what;
  }
}

std::string run_cli(const std::string& args, const std::string& log, int& status) {
  const std::string command = test::leakmon_binary() + " " + args + " > " + log + " 2>&1";
  status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The command line: a rig file's error at file:line:column, an unknown actuator likewise, and
// the options that go together or exclude each other. Each fails before any capture is read.
TEST(ModelCheckCli, RigOptionsAndTheirErrors) {
  const std::string dir = test::scratch_dir("model_rig_cli");
  const std::string capture = write(dir + "/capture.csv", "t,u,x,p1,p2\n0,0,0,0,0\n");
  const std::string rig =
      write(dir + "/rig.yaml", "rig:\n  supply_pressure: 21.0e6\n  stroke: -1\n");
  const std::string config = write(dir + "/leakmon.yaml", "actuators:\n  - name: press\n");
  const std::string common = "model check --data " + capture + " --json " + dir + "/r.json ";
  int status = 0;
  std::string log = run_cli(common + "--rig " + rig, dir + "/1.log", status);
  EXPECT_NE(status, 0);
  EXPECT_NE(log.find(rig + ":3:"), std::string::npos) << log;
  EXPECT_NE(log.find("stroke"), std::string::npos) << log;
  log = run_cli(common + "--config " + config + " --actuator crane", dir + "/2.log", status);
  EXPECT_NE(status, 0);
  EXPECT_NE(log.find(config + ":2:"), std::string::npos) << log;
  EXPECT_NE(log.find("crane"), std::string::npos) << log;
  log = run_cli(common + "--config " + config, dir + "/3.log", status);
  EXPECT_NE(status, 0);
  EXPECT_NE(log.find("--actuator"), std::string::npos) << log;
  log = run_cli(common + "--rig " + rig + " --config " + config + " --actuator press",
                dir + "/4.log", status);
  EXPECT_NE(status, 0);
  EXPECT_NE(log.find("give the rig once"), std::string::npos) << log;
}

}  // namespace
}  // namespace leakmon::model
