#include "sim/simulate.hpp"

#include <fmt/format.h>

#include <array>
#include <span>
#include <variant>

#include "sim/rig.hpp"

namespace leakmon::sim {
namespace {

const std::vector<std::string> kColumns = {"t", "xref", "u", "x", "p1", "p2", "q_int"};

// The capture's columns: the fixed seven, then the optional ones the scenario records.
std::vector<std::string> columns(const Scenario& scenario) {
  std::vector<std::string> out = kColumns;
  if (scenario.record.ps) out.emplace_back("ps");
  if (scenario.record.temp) out.emplace_back("temp");
  return out;
}

// One row in the order of columns(); returns the number of values.
std::size_t row(const Scenario& scenario, const RigSample& s, std::array<double, 9>& out) {
  out = {s.t, s.xref, s.u, s.x, s.p1, s.p2, s.q_int, 0.0, 0.0};
  std::size_t n = 7;
  if (scenario.record.ps) out[n++] = s.ps;
  if (scenario.record.temp) out[n++] = s.temp;
  return n;
}

std::string format_params(const std::vector<EffectParameter>& params) {
  std::string out;
  for (const auto& param : params) {
    if (!out.empty()) out += ' ';
    if (const double* value = std::get_if<double>(&param.value)) {
      out += fmt::format("{}={:g}", param.name, *value);
    } else {
      out += fmt::format("{}={}", param.name, std::get<std::string>(param.value));
    }
  }
  return out;
}

// Parameters that differ from MODEL.md's nominal table, "name=value" separated by spaces.
std::string overridden_parameters(const Parameters& p) {
  const Parameters n = Parameters::nominal();
  std::string out;
  const auto check = [&](std::string_view name, double value, double nominal) {
    if (value == nominal) return;
    if (!out.empty()) out += ' ';
    out += fmt::format("{}={:g}", name, value);
  };
  check("D", p.D, n.D);
  check("d", p.d, n.d);
  check("L", p.L, n.L);
  check("V_dead", p.V_dead, n.V_dead);
  check("V_line", p.V_line, n.V_line);
  check("ps", p.ps, n.ps);
  check("pt", p.pt, n.pt);
  check("beta", p.beta, n.beta);
  check("m", p.m, n.m);
  check("b", p.b, n.b);
  check("K_s", p.K_s, n.K_s);
  check("Kv", p.Kv, n.Kv);
  check("tau", p.tau, n.tau);
  check("u_max", p.u_max, n.u_max);
  check("dp_lin", p.dp_lin, n.dp_lin);
  check("C_n", p.C_n, n.C_n);
  check("sigma_w", p.sigma_w, n.sigma_w);
  check("tau_w", p.tau_w, n.tau_w);
  check("K_stop", p.K_stop, n.K_stop);
  check("c_stop", p.c_stop, n.c_stop);
  return out;
}

// "hold 0.02 for 180 s; steps for 300 s; ...; triangle 4 0.03 to the end".
std::string program_description(const std::vector<Phase>& program) {
  std::string out;
  for (std::size_t i = 0; i < program.size(); ++i) {
    if (i > 0) out += "; ";
    out += program[i].notation();
    if (i + 1 < program.size()) {
      out += fmt::format(" for {:.10g} s", program[i].duration_s);
    } else if (program[i].duration_s > 0.0) {
      out += fmt::format(" (T {:.10g} s) to the end", program[i].duration_s);
    } else {
      out += " to the end";
    }
  }
  return out;
}

}  // namespace

capture::Metadata capture_metadata(const Scenario& scenario) {
  capture::Metadata meta;
  meta.emplace_back("sample_rate_hz", fmt::format("{:g}", scenario.sample_rate_hz));
  meta.emplace_back(
      "source", fmt::format("sim {} seed {}",
                            scenario.origin.empty() ? "scenario " + scenario.name : scenario.origin,
                            scenario.seed));
  meta.emplace_back("scenario", scenario.name);
  meta.emplace_back("seed", fmt::format("{}", scenario.seed));
  meta.emplace_back("controller", std::string(to_string(scenario.controller)));
  meta.emplace_back("duration_s", fmt::format("{:g}", scenario.duration_s));
  meta.emplace_back("integration_step_s", fmt::format("{:g}", integration_step(scenario)));
  const auto effects = scenario.effects.describe();
  if (effects.empty()) meta.emplace_back("effects", "none");
  for (const auto& effect : effects) {
    meta.emplace_back("effect", fmt::format("{} {}", effect.name, format_params(effect.params)));
  }
  if (scenario.change) {
    std::string appearing;
    for (const auto& effect : scenario.change->effects.describe()) {
      appearing += fmt::format("{}{} {}", appearing.empty() ? "" : "; ", effect.name,
                               format_params(effect.params));
    }
    meta.emplace_back("effect_change",
                      fmt::format("t_s={:g} effects {}", scenario.change->t_s,
                                  appearing.empty() ? std::string("none") : appearing));
  }
  // Listed only for another rig, so that the paper's captures read as before.
  if (!scenario.rig.nominal()) meta.emplace_back("rig", describe(scenario.rig));
  const std::string overrides = overridden_parameters(scenario.params);
  meta.emplace_back("params", overrides.empty() ? "nominal" : overrides);
  const SensorSettings& s = scenario.sensors;
  meta.emplace_back(
      "sensors",
      s.enabled
          ? fmt::format("pressure {} bit 0..{:g} Pa{} noise {:g} Pa; position resolution {:g} m{} "
                        "noise {:g} m",
                        s.pressure_bits, s.pressure_full_scale,
                        s.pressure_quantisation ? "" : " (unquantised)", s.pressure_noise_sigma,
                        s.position_resolution, s.position_quantisation ? "" : " (unquantised)",
                        s.position_noise_sigma)
          : std::string("ideal (true values)"));
  // A test program, drifting conditions, faults and optional transducers: listed only when
  // present, so that a stationary scenario on the paper's steps reads as before.
  if (!scenario.program.empty()) {
    meta.emplace_back("program", program_description(scenario.program));
    // One line per phase with where it sits in this run, for scoring per phase.
    const auto spans = phase_spans(scenario.program, scenario.duration_s);
    for (std::size_t i = 0; i < spans.size(); ++i) {
      meta.emplace_back(
          "phase", fmt::format("{} start_s={:.10g} end_s={:.10g}", scenario.program[i].notation(),
                               spans[i].start, spans[i].end));
    }
  }
  const OperatingConditions& c = scenario.conditions;
  if (c.temperature) {
    meta.emplace_back("oil", fmt::format("{}nu40={:g} nu100={:g} (Walther, ASTM D341)",
                                         c.oil.name().empty() ? "" : c.oil.name() + " ",
                                         c.oil.nu40(), c.oil.nu100()));
    meta.emplace_back("temperature", c.temperature->describe());
  }
  for (const SupplyChange& change : c.supply) {
    meta.emplace_back("supply_change", fmt::format("t_s={:g} ps={:g} ramp_s={:g}", change.t_s,
                                                   change.ps, change.ramp_s));
  }
  for (const SensorFault& fault : scenario.faults) {
    meta.emplace_back("sensor_fault", fault.describe());
  }
  if (scenario.record.ps) {
    meta.emplace_back("ps_sensor", "supply pressure, the pressure chain above");
  }
  if (scenario.record.temp) {
    meta.emplace_back(
        "temp_sensor",
        s.enabled ? fmt::format("RTD resolution {:g} K noise {:g} K range {:g}..{:g} degC",
                                s.temp_resolution, s.temp_noise_sigma, s.temp_min, s.temp_max)
                  : std::string("ideal (true values)"));
  }
  return meta;
}

capture::Capture simulate(const Scenario& scenario) {
  capture::Capture capture;
  capture.metadata = capture_metadata(scenario);
  capture.columns = columns(scenario);
  const std::uint64_t n = scenario.samples();
  capture.values.assign(capture.columns.size(), std::vector<double>(n));
  Rig rig(scenario);
  std::array<double, 9> values{};
  for (std::uint64_t k = 0; k < n; ++k) {
    const std::size_t count = row(scenario, rig.step(), values);
    for (std::size_t c = 0; c < count; ++c) capture.values[c][k] = values[c];
  }
  return capture;
}

void simulate_to_file(const Scenario& scenario, const std::string& path) {
  capture::CaptureWriter writer(path, columns(scenario), capture_metadata(scenario));
  Rig rig(scenario);
  const std::uint64_t n = scenario.samples();
  std::array<double, 9> values{};
  for (std::uint64_t k = 0; k < n; ++k) {
    const std::size_t count = row(scenario, rig.step(), values);
    writer.write_row(std::span<const double>(values.data(), count));
  }
  writer.close();
}

}  // namespace leakmon::sim
