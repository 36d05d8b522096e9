#include "model/synthetic_case.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "model/effect_library.hpp"
#include "sim/rig_draw.hpp"
#include "sim/simulate.hpp"

namespace leakmon::model {
namespace {

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(engine_); }
  // Log-uniform: leak sizes and resistances span an order of magnitude.
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  double sign() { return uniform(0.0, 1.0) < 0.5 ? -1.0 : 1.0; }
  bool coin() { return uniform(0.0, 1.0) < 0.5; }
  std::size_t index(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(engine_);
  }
  std::uint64_t seed() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

// A stream of the case's seed for the other rig, apart from the draws below (so that the
// paper's cases draw exactly what they drew before other rigs existed).
constexpr std::uint64_t kOtherRigStream = 0x6f746865722d7267ULL;  // "other-rg"
constexpr std::uint64_t kProgramStream = 0x70726f6772616d73ULL;   // "programs"

}  // namespace

const std::vector<Misstatement>& misstatements() {
  static const std::vector<Misstatement> list = {{"supply_pressure", 0.15, 0.30},
                                                 {"load_stiffness", 0.40, 0.80}};
  return list;
}

namespace {

// A test program (MODEL.md "Test programs") in place of the steps, drawn from its own stream so
// that the rig and its effects are those of the same seed without a program. Its 3-8 phases
// are shortened alike so that every one of them runs within the capture (MODEL.md's phases last
// minutes), positions and amplitudes scaled as the rig's steps are (another rig's steps are
// smaller where its valve cannot make the paper's), and drawn again while the rig cannot run it
// (sim::check_viability; after kProgramDraws tries at half the amplitudes, and so on).
std::vector<sim::Phase> capture_program(std::uint64_t seed, const sim::Scenario& on_rig) {
  constexpr int kProgramDraws = 6;
  std::mt19937_64 rng(seed ^ kProgramStream);
  double scale = on_rig.reference.amp_max / sim::ReferenceSettings{}.amp_max;
  sim::Scenario trial = on_rig;
  for (int attempt = 1;; ++attempt) {
    int no_leak_phase = -1;
    std::vector<sim::Phase> program = sim::draw_program(rng, 1.0, std::nullopt, no_leak_phase);
    const double shorten = on_rig.duration_s / sim::program_seconds(program);
    for (auto& phase : program) {
      phase.duration_s *= shorten;
      phase.X *= scale;
      phase.A *= scale;
    }
    trial.program = program;
    if (attempt >= 4 * kProgramDraws || sim::check_viability(trial, trial.duration_s).ok) {
      return program;
    }
    if (attempt % kProgramDraws == 0) scale *= 0.5;
  }
}

}  // namespace

SyntheticCase draw_case(std::uint64_t seed, const std::string& effect,
                        const CaseSettings& settings) {
  Draw draw(seed);
  SyntheticCase c;
  c.seed = seed;
  const auto& names = effect_names();
  if (effect.empty()) {
    const std::size_t i = draw.index(names.size() + 1);
    c.effect = i < names.size() ? names[i] : "none";
  } else {
    c.effect = effect;
  }
  auto& s = c.scenario;
  s.name = fmt::format("model-check case {} ({})", seed, c.effect);
  s.origin = fmt::format("model check synthetic case seed {}", seed);
  s.controller = draw.coin() ? sim::ControllerKind::basic : sim::ControllerKind::fault_tolerant;
  s.duration_s = settings.duration_s;
  s.seed = draw.seed();
  if (settings.other_rig) {
    // Another rig the controller runs, drawn from its own stream; a spring to mis-state.
    Draw rig_draw(seed ^ kOtherRigStream);
    sim::OtherRig other = sim::draw_other_rig(rig_draw.seed(), s.controller);
    while (settings.misstate == "load_stiffness" && other.rig.params.K_s <= 0.0) {
      other = sim::draw_other_rig(rig_draw.seed(), s.controller);
    }
    const sim::Scenario on_rig = sim::other_rig_scenario(other, s.controller, s.duration_s, s.seed);
    s.rig = on_rig.rig;
    s.params = on_rig.params;
    s.conditions = on_rig.conditions;
    s.reference = on_rig.reference;
    s.sensors = on_rig.sensors;
  }
  c.told = s.rig;
  // Calibratable parameters within MODEL.md's ranges: not a discrepancy to report.
  s.params.beta *= draw.uniform(0.75, 1.25);
  s.params.Kv *= draw.uniform(0.9, 1.1);
  s.params.m *= draw.uniform(0.8, 1.2);
  s.params.b *= draw.uniform(0.7, 1.3);
  if (!settings.misstate.empty()) {
    const auto known =
        std::find_if(misstatements().begin(), misstatements().end(),
                     [&](const Misstatement& m) { return m.key == settings.misstate; });
    if (known == misstatements().end()) {
      throw std::invalid_argument(fmt::format("no misstatement of '{}'", settings.misstate));
    }
    const double off = draw.uniform(known->low, known->high);
    const double factor = draw.coin() ? 1.0 + off : 1.0 - off;
    c.misstated = known->key;
    c.misstated_true = *sim::rig_value(c.told, known->key);
    c.told = sim::misstate(c.told, known->key, factor);
    c.misstated_stated = *sim::rig_value(c.told, known->key);
  }
  // How large each effect is on this rig (the paper's: 1).
  const RigScales size = RigScales::of(s.params);

  auto& e = s.effects;
  // The main parameter's value: drawn within MODEL.md's range, or (settings.edge > 0) at its
  // low end divided by `edge` or its high end times `edge`.
  const auto in_range = [&](double lo, double hi, bool log) {
    if (settings.edge > 0.0) return draw.coin() ? hi * settings.edge : lo / settings.edge;
    return log ? draw.log_uniform(lo, hi) : draw.uniform(lo, hi);
  };
  const auto channel = [&] {
    return draw.coin() ? sim::PressureChannel::p1 : sim::PressureChannel::p2;
  };
  // "a+b": several effects at once, each drawn in turn; the first one is the case's main.
  std::vector<std::string> parts;
  for (std::size_t begin = 0; begin <= c.effect.size();) {
    const std::size_t end = std::min(c.effect.find('+', begin), c.effect.size());
    parts.push_back(c.effect.substr(begin, end - begin));
    begin = end + 1;
  }
  for (const auto& part : parts) {
    TrueEffect t{part, "", 0.0};
    const auto set_main = [&](const char* name, double value) {
      t.main_parameter = name;
      t.main_value = value;
      return value;
    };
    if (part == "internal_leakage") {
      e.internal_leakage =
          sim::InternalLeakage{set_main("C_L", size.leak * in_range(5e-13, 5e-12, true))};
    } else if (part == "external_leakage") {
      const double ce = set_main("C_E", size.leak * in_range(1e-13, 2e-12, true));
      e.external_leakage = sim::ExternalLeakage{ce, draw.coin() ? 1 : 2};
    } else if (part == "coulomb_friction") {
      e.coulomb_friction =
          sim::CoulombFriction{set_main("F_C", size.force * in_range(50.0, 400.0, false))};
    } else if (part == "entrained_air") {
      e.entrained_air = sim::EntrainedAir{set_main("alpha", in_range(0.02, 0.2, true))};
    } else if (part == "valve_overlap") {
      e.valve_overlap = sim::ValveOverlap{set_main("d", in_range(0.01, 0.05, false))};
    } else if (part == "valve_bias") {
      e.valve_bias =
          sim::ValveBias{set_main("u0", size.command * draw.sign() * in_range(0.05, 0.3, false))};
    } else if (part == "spool_lag") {
      // The paper's 6-15 ms for its 2.5 ms spool: 2.4-6 times the rig's own.
      e.spool_lag = sim::SpoolLag{
          set_main("tau", s.params.tau / sim::Parameters{}.tau * in_range(0.006, 0.015, false))};
    } else if (part == "supply_ripple") {
      const double dp = set_main("dP", in_range(2e5, 1e6, false));
      e.supply_ripple = sim::SupplyRipple{dp, draw.uniform(20.0, 200.0)};
    } else if (part == "supply_droop") {
      e.supply_droop = sim::SupplyDroop{set_main("R_s", size.droop * in_range(5e9, 3e10, true))};
    } else if (part == "sensor_offset") {
      const double offset = set_main("offset", draw.sign() * in_range(5e4, 3e5, false));
      e.sensor_offset = sim::SensorOffset{offset, channel()};
    } else if (part == "sensor_lag") {
      e.sensor_lag = sim::SensorLag{set_main("tau_s", in_range(0.002, 0.01, false)), channel()};
    } else if (part == "oil_temperature") {
      // A warm-up within the capture (MODEL.md "Drifting operating conditions"): from a cold
      // start towards the working temperature, in one of the three oils of its table.
      const int grades[] = {32, 46, 68};
      s.conditions.oil = *sim::Oil::iso_vg(grades[draw.index(3)]);
      sim::TemperatureProfile warm_up;
      warm_up.kind = sim::TemperatureProfile::Kind::warm_up;
      warm_up.T0 = draw.uniform(15.0, 28.0);
      warm_up.T_work = draw.uniform(40.0, 50.0);
      warm_up.tau_s = settings.duration_s * draw.uniform(0.3, 1.0);
      warm_up.start_s = 0.0;
      s.conditions.temperature = warm_up;
      s.record.temp = settings.record_temperature;
      set_main("visc_slope", s.conditions.oil.viscosity_slope(sim::kReferenceTemperature));
    } else if (part != "none") {
      throw std::invalid_argument(fmt::format("unknown effect '{}'", part));
    }
    if (part != "none") c.effects.push_back(t);
  }
  if (!c.effects.empty()) {
    c.main_parameter = c.effects.front().main_parameter;
    c.main_value = c.effects.front().main_value;
  }
  if (settings.onset && e.any()) {
    // The effects appear inside the capture: none before the onset, all of them after it.
    const double dt = 1.0 / s.sample_rate_hz;
    c.onset_s = std::round(draw.uniform(0.2, 0.8) * settings.duration_s / dt) * dt;
    s.change = sim::EffectChange{c.onset_s, e};
    e = sim::Effects{};
  }
  if (settings.program) c.scenario.program = capture_program(seed, s);
  return c;
}

capture::Capture simulate_case(const SyntheticCase& c) { return sim::simulate(c.scenario); }

ModelParameters true_model(const SyntheticCase& c) {
  const auto& s = c.scenario;
  ModelParameters m;
  m.calibration = {s.params.beta, s.params.Kv, s.params.m, s.params.b};
  // Effects that appear inside the capture: the true model switches at their onset (the
  // effects before it are none, as drawn).
  if (s.change) m.onset_s = s.change->t_s;
  const auto& e = s.change ? s.change->effects : s.effects;
  auto& t = m.effects;
  const auto channel = [](sim::PressureChannel ch) {
    return ch == sim::PressureChannel::p1 ? PressureChannel::p1 : PressureChannel::p2;
  };
  if (e.internal_leakage) t.C_L = e.internal_leakage->C_L;
  if (e.external_leakage) {
    t.C_E = e.external_leakage->C_E;
    t.external_chamber = e.external_leakage->chamber;
  }
  if (e.coulomb_friction) t.F_C = e.coulomb_friction->F_C;
  if (e.entrained_air) t.alpha = e.entrained_air->alpha;
  if (e.valve_overlap) t.d = e.valve_overlap->d;
  if (e.valve_bias) t.u0 = e.valve_bias->u0;
  if (e.spool_lag) t.spool_tau = e.spool_lag->tau;
  if (e.supply_ripple) {
    t.ripple_dP = e.supply_ripple->dP;
    t.ripple_f = e.supply_ripple->f;
  }
  if (e.supply_droop) t.R_s = e.supply_droop->R_s;
  if (e.sensor_offset) {
    t.offset = e.sensor_offset->offset;
    t.offset_channel = channel(e.sensor_offset->channel);
  }
  if (e.sensor_lag) {
    t.tau_s = e.sensor_lag->tau_s;
    t.lag_channel = channel(e.sensor_lag->channel);
  }
  if (s.conditions.temperature) {
    t.visc_slope = s.conditions.oil.viscosity_slope(sim::kReferenceTemperature);
  }
  return m;
}

}  // namespace leakmon::model
