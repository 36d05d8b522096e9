// The pressure-only detector (index_cusum) on the simulated rig of MODEL.md while its oil warms
// up, cycles with the cooler and its supply set-point moves: the wavelet index and the hop means
// as the daemon forms them (StreamingFeatures over p1 and p2, 20-sample hops; the daemon's own
// path is covered by the replay tests), fed straight to the detector, with and without the
// temp and ps observations, with p1 and p2 and with p1 alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "detect/index_cusum_detector.hpp"
#include "dsp/streaming_features.hpp"
#include "sim/simulate.hpp"

namespace leakmon::detect {
namespace {

constexpr std::size_t kStep = 20;  // samples per hop at 500 Hz
constexpr double kHop = 0.04;

// Every hop's observation with all channels; a run drops the ones it does not acquire.
std::vector<Observation> observations_of(const sim::Scenario& scenario) {
  const capture::Capture capture = sim::simulate(scenario);
  const auto& t = capture.column("t");
  const auto& p1 = capture.column("p1");
  const auto& p2 = capture.column("p2");
  const std::vector<double>* temp = scenario.record.temp ? &capture.column("temp") : nullptr;
  const std::vector<double>* ps = scenario.record.ps ? &capture.column("ps") : nullptr;
  dsp::StreamingFeatures features(dsp::FeatureParams{}, 2);
  std::vector<Observation> out;
  out.reserve(capture.rows() / kStep + 1);
  double sums[4] = {0, 0, 0, 0};
  std::size_t in_hop = 0;
  for (std::size_t i = 0; i < capture.rows(); ++i) {
    const double sample[2] = {p1[i], p2[i]};
    sums[0] += p1[i];
    sums[1] += p2[i];
    sums[2] += temp != nullptr ? (*temp)[i] : kMissing;
    sums[3] += ps != nullptr ? (*ps)[i] : kMissing;
    ++in_hop;
    if (!features.push(sample)) continue;
    const auto latest = features.latest();
    Observation o;
    o.t = t[i];
    o.index_p1 = latest[0].valid ? latest[0].rms : kMissing;
    o.index_p2 = latest[1].valid ? latest[1].rms : kMissing;
    const double n = static_cast<double>(in_hop);
    o.p1 = sums[0] / n;
    o.p2 = sums[1] / n;
    o.temp = sums[2] / n;
    o.ps = sums[3] / n;
    out.push_back(o);
    sums[0] = sums[1] = sums[2] = sums[3] = 0.0;
    in_hop = 0;
  }
  return out;
}

struct Acquired {
  bool p2 = true, temp = false, ps = false;
};

struct Outcome {
  int false_alarms = 0;       // raises before the onset (re-armed when the score clears)
  double monitored_s = 0.0;   // judged time before the onset
  double first_raise = -1.0;  // first raise at or after the onset
  double max_score_before = 0.0;
  double t_max_score = 0.0;  // when it was reached
};

Outcome run(const std::vector<Observation>& stream, const Acquired& acquired, double onset,
            IndexCusumOptions options = {}) {
  options.use_p2 = acquired.p2;
  IndexCusumDetector detector(options, kHop);
  Outcome outcome;
  bool raised = false;
  for (Observation o : stream) {
    if (!acquired.p2) o.p2 = o.index_p2 = kMissing;
    if (!acquired.temp) o.temp = kMissing;
    if (!acquired.ps) o.ps = kMissing;
    const Decision d = detector.update(o);
    if (d.learning) continue;
    if (o.t < onset) outcome.monitored_s += kHop;
    if (std::isnan(d.score)) continue;
    if (o.t < onset && d.score > outcome.max_score_before) {
      outcome.max_score_before = d.score;
      outcome.t_max_score = o.t;
    }
    if (!raised && d.score >= detector.raise_threshold()) {
      raised = true;
      if (o.t < onset) {
        ++outcome.false_alarms;
      } else if (outcome.first_raise < 0.0) {
        outcome.first_raise = o.t;
      }
    } else if (raised && d.score <= detector.clear_threshold()) {
      raised = false;
    }
  }
  return outcome;
}

sim::TemperatureProfile warm_up_profile(double T0, double tau) {
  sim::TemperatureProfile p;
  p.kind = sim::TemperatureProfile::Kind::warm_up;
  p.T0 = T0;
  p.T_work = 50.0;
  p.tau_s = tau;
  return p;
}

sim::Scenario base(std::uint64_t seed, bool fault_tolerant, double seconds) {
  sim::Scenario s;
  s.controller = fault_tolerant ? sim::ControllerKind::fault_tolerant : sim::ControllerKind::basic;
  s.seed = seed;
  s.duration_s = seconds;
  s.record.temp = true;
  s.record.ps = true;
  return s;
}

struct Case {
  const char* name;
  sim::Scenario scenario;
  double onset = 1e300;
};

std::vector<Case> drift_cases(std::uint64_t seed) {
  std::vector<Case> cases;
  for (const bool ft : {false, true}) {
    {
      sim::Scenario s = base(seed, ft, 1800.0);
      s.conditions.temperature = warm_up_profile(20.0, 600.0);
      cases.push_back({"warm-up 20->50 tau 600", s});
    }
    {
      sim::Scenario s = base(seed + 1, ft, 1800.0);
      auto p = warm_up_profile(15.0, 300.0);
      p.T_work = 55.0;
      p.kind = sim::TemperatureProfile::Kind::warm_up_cooler;
      p.amplitude = 4.0;
      p.period_s = 300.0;
      p.cooler_start_s = 900.0;
      s.conditions.temperature = p;
      cases.push_back({"warm-up 15->55 tau 300 + cooler 4K/300s", s});
    }
    for (const auto& [amplitude, period] : {std::pair{4.0, 300.0}, std::pair{2.0, 1200.0}}) {
      sim::Scenario s = base(seed + 2, ft, 1800.0);
      sim::TemperatureProfile p;
      p.kind = sim::TemperatureProfile::Kind::cooler;
      p.T_work = 48.0;
      p.amplitude = amplitude;
      p.period_s = period;
      p.cooler_start_s = 120.0;
      s.conditions.temperature = p;
      cases.push_back({period < 600 ? "cooler 4K/300s" : "cooler 2K/1200s", s});
    }
    {
      // End of shift: learned warm, then the oil cools from 50 to 30 degC (tau 300 s).
      sim::Scenario s = base(seed + 4, ft, 1800.0);
      auto p = warm_up_profile(50.0, 300.0);
      p.T_work = 30.0;
      p.start_s = 300.0;
      s.conditions.temperature = p;
      cases.push_back({"cool-down 50->30 tau 300 from 300 s", s});
    }
    {
      sim::Scenario s = base(seed + 5, ft, 1500.0 + 120.0);
      s.conditions.temperature = warm_up_profile(20.0, 300.0);
      s.effects.internal_leakage = sim::InternalLeakage{2e-12, 1500.0, 0.0};
      cases.push_back({"leak 2e-12 at 1500 s after warm-up tau 300", s, 1500.0});
    }
    {
      sim::Scenario s = base(seed + 6, ft, 600.0 + 120.0);
      s.effects.internal_leakage = sim::InternalLeakage{2e-12, 600.0, 0.0};
      cases.push_back({"leak 2e-12 at 600 s, 40 degC", s, 600.0});
    }
    {
      sim::Scenario s = base(seed + 3, ft, 1200.0);
      s.conditions.supply = {{300.0, 14e6, 2.0}, {700.0, 20e6, 0.0}};
      cases.push_back({"supply 17.2->14->20 MPa", s});
    }
  }
  return cases;
}

// Measurement: every case with every acquisition, printed (not asserted here; the assertions are
// in the tests below). LEAKMON_INDEX_SEEDS=N runs N seeds.
TEST(IndexCusumOnTheSimulatedRig, Survey) {
  const char* env = std::getenv("LEAKMON_INDEX_SEEDS");
  const int seeds = env != nullptr ? std::atoi(env) : 0;
  const char* only = std::getenv("LEAKMON_INDEX_CASE");
  const int first =
      std::getenv("LEAKMON_INDEX_FIRST") ? std::atoi(std::getenv("LEAKMON_INDEX_FIRST")) : 0;
  for (int k = first; k < seeds; ++k) {
    for (const auto& c : drift_cases(100 + 10 * static_cast<std::uint64_t>(k))) {
      if (only != nullptr && std::string(c.name).find(only) == std::string::npos) continue;
      const auto stream = observations_of(c.scenario);
      for (const Acquired a : {Acquired{true, false, false}, Acquired{false, false, false},
                               Acquired{true, true, true}, Acquired{false, true, true}}) {
        if (std::getenv("LEAKMON_INDEX_TEMP") && !a.temp) continue;
        const Outcome o = run(stream, a, c.onset);
        std::printf(
            "SURVEY seed %d ctl %d %-42s p2 %d temp %d ps %d: alarms %d in %.3f h, max %.2f, raise "
            "%.1f\n",
            k, static_cast<int>(c.scenario.controller), c.name, a.p2, a.temp, a.ps, o.false_alarms,
            o.monitored_s / 3600.0, o.max_score_before,
            o.first_raise < 0 ? -1.0 : o.first_raise - c.onset);
      }
    }
  }
}

// Fixed seeds (the survey's first), both controllers, every acquisition (p1 alone without ps
// reads the supply from its hold levels).
TEST(IndexCusumOnTheSimulatedRig, DriftRaisesNothing) {
  for (const auto& c : drift_cases(100)) {
    const std::string name = c.name;
    if (c.onset < 1e300 || name.find("warm-up 20") != std::string::npos ||
        name.find("2K") != std::string::npos) {
      continue;  // leaks below; the milder drifts are in the survey
    }
    const auto stream = observations_of(c.scenario);
    for (const Acquired a : {Acquired{true, false, false}, Acquired{false, false, false},
                             Acquired{true, true, true}, Acquired{false, true, true}}) {
      const Outcome o = run(stream, a, c.onset);
      std::printf("controller %d %s, p2 %d temp %d ps %d: max score %.2f\n",
                  static_cast<int>(c.scenario.controller), c.name, a.p2, a.temp, a.ps,
                  o.max_score_before);
      EXPECT_EQ(o.false_alarms, 0) << c.name << " p2 " << a.p2 << " temp " << a.temp;
      EXPECT_LT(o.max_score_before, 1.0) << c.name << " p2 " << a.p2 << " temp " << a.temp;
    }
  }
}

// 2e-12 m^3/(s Pa) at 1500 s, after a warm-up from 20 to 50 degC (tau 300 s): the index rose by
// about 15 % above what was learned, so a stationary detector judged the leak against a baseline
// that was too low (seed 105: 85 s and 24 s, and never within 120 s for another seed).
TEST(IndexCusumOnTheSimulatedRig, ALeakAfterTheWarmUpIsFound) {
  for (const auto& c : drift_cases(100)) {
    if (std::string(c.name).find("after warm-up") == std::string::npos) continue;
    const auto stream = observations_of(c.scenario);
    for (const Acquired a :
         {Acquired{true, false, false}, Acquired{true, true, true}, Acquired{false, true, true}}) {
      const Outcome o = run(stream, a, c.onset);
      std::printf(
          "controller %d, p2 %d temp %d: max before %.2f (t %.0f s), found %.1f s after the "
          "onset\n",
          static_cast<int>(c.scenario.controller), a.p2, a.temp, o.max_score_before, o.t_max_score,
          o.first_raise - c.onset);
      EXPECT_EQ(o.false_alarms, 0) << "p2 " << a.p2 << " temp " << a.temp;
      EXPECT_GT(o.first_raise, c.onset) << "p2 " << a.p2 << " temp " << a.temp;
      EXPECT_LT(o.first_raise, c.onset + 90.0) << "p2 " << a.p2 << " temp " << a.temp;
    }
  }
}

// p1 alone, no ps channel: the supply lowered from 17.2 to 14 MPa at 300 s (a 2 s ramp) and
// raised to 20 MPa at 700 s. Before the supply was read from p1's hold levels the lowered
// supply's smaller index was a leak: with this seed (the survey's second) the score reached 3.4
// (basic controller) and 3.1 (fault tolerant), one false alarm each. A leak of 2e-12 opening at
// 20 MPa is still found.
TEST(IndexCusumOnTheSimulatedRig, POneAloneFollowsTheSupplyFromItsHoldLevels) {
  for (const bool ft : {false, true}) {
    sim::Scenario s = base(113, ft, 1200.0);
    s.conditions.supply = {{300.0, 14e6, 2.0}, {700.0, 20e6, 0.0}};
    const Outcome healthy = run(observations_of(s), Acquired{false, false, false}, 1e300);
    std::printf("controller %d, p1 alone: max score %.2f (t %.0f s)\n", ft,
                healthy.max_score_before, healthy.t_max_score);
    EXPECT_EQ(healthy.false_alarms, 0) << "controller " << ft;
    EXPECT_LT(healthy.max_score_before, 1.0) << "controller " << ft;

    s.effects.internal_leakage = sim::InternalLeakage{2e-12, 1000.0, 0.0};
    s.duration_s = 1000.0 + 120.0;
    const Outcome leak = run(observations_of(s), Acquired{false, false, false}, 1000.0);
    std::printf("controller %d, p1 alone: leak found %.1f s after the onset\n", ft,
                leak.first_raise - 1000.0);
    EXPECT_EQ(leak.false_alarms, 0) << "controller " << ft;
    EXPECT_GT(leak.first_raise, 1000.0) << "controller " << ft;
    EXPECT_LT(leak.first_raise, 1000.0 + 120.0) << "controller " << ft;
  }
}

}  // namespace
}  // namespace leakmon::detect
