#include "model/result_json.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string_view>

namespace leakmon::model {
namespace {

std::string number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

std::string params_object(const std::vector<NamedValue>& params) {
  std::string out = "{";
  for (std::size_t i = 0; i < params.size(); ++i) {
    const auto& p = params[i];
    out += fmt::format("{}\"{}\": ", i ? ", " : "", p.name);
    if (p.is_text()) {
      out += fmt::format("\"{}\"", p.text);
    } else if (p.name == "chamber") {
      out += fmt::format("{}", static_cast<int>(p.value));
    } else {
      out += number(p.value);
    }
  }
  return out + "}";
}

std::string errors_object(const std::vector<NamedValue>& params) {
  std::string out = "{";
  bool first = true;
  for (const auto& p : params) {
    // Discrete values have no error, nor has a rig_parameter's stated value.
    if (p.is_text() || p.name == "chamber" || p.name == "stated") continue;
    out += fmt::format("{}\"{}\": {}", first ? "" : ", ", p.name, number(p.error));
    first = false;
  }
  return out + "}";
}

std::string string_list(const std::vector<std::string>& names) {
  std::string out = "[";
  for (std::size_t i = 0; i < names.size(); ++i) {
    out += fmt::format("{}\"{}\"", i ? ", " : "", names[i]);
  }
  return out + "]";
}

std::string channel_object(const std::array<double, 3>& v) {
  return fmt::format("{{\"x\": {}, \"p1\": {}, \"p2\": {}}}", number(v[0]), number(v[1]),
                     number(v[2]));
}

std::string misfit_object(const Misfit& m) {
  std::string regressors = "{";
  for (std::size_t i = 0; i < m.regressors.size(); ++i) {
    regressors += fmt::format("{}\"{}\": {}", i ? ", " : "", m.regressors[i].regressor,
                              number(m.regressors[i].correlation));
  }
  regressors += "}";
  return fmt::format(
      "{{\"channel\": \"{}\", \"regressor\": \"{}\", \"correlation\": {}, "
      "\"regressors\": {}, \"band_hz\": [{}, {}], \"band_share\": {}, \"drifts\": {}, "
      "\"late_over_early\": {}, \"trend_t\": {}, \"channel_nrmse\": {}, "
      "\"channel_floor\": {}}}",
      m.channel, m.regressors.empty() ? "" : m.regressors[0].regressor,
      number(m.regressors.empty() ? 0.0 : m.regressors[0].correlation), regressors,
      number(m.band_low_hz), number(m.band_high_hz), number(m.band_share),
      m.drifts ? "true" : "false", number(m.late_over_early), number(m.trend_t),
      channel_object(m.channel_nrmse), channel_object(m.channel_floor));
}

std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string findings_list(const std::vector<RigFinding>& findings) {
  std::string out = "[";
  for (std::size_t i = 0; i < findings.size(); ++i) {
    const auto& f = findings[i];
    out += fmt::format("{}{{\"parameter\": \"{}\", \"stated\": {}, \"fitted\": {}, \"error\": {}}}",
                       i ? ", " : "", f.parameter, number(f.stated), number(f.fitted),
                       number(f.error));
  }
  return out + "]";
}

// The rig's keys with their values (sim::rig_value), every key of MODEL.md's table but the
// data-sheet alternatives (valve rating, oil viscosities) that restate another.
std::string rig_values(const sim::RigDescription& rig) {
  std::string out = "{";
  bool first = true;
  for (const auto& key : sim::rig_keys()) {
    if (key.symbol.empty()) continue;
    const auto value = sim::rig_value(rig, key.key);
    if (!value) continue;
    out += fmt::format("{}\"{}\": {}", first ? "" : ", ", key.key, number(*value));
    first = false;
  }
  return out + "}";
}

// What the model check assumed about the rig (FORMATS.md: the report states it): the
// description, the values stated and assumed, the values checked and the evidence.
std::string rig_object(const Diagnosis& d) {
  sim::RigDescription assumed = d.rig;
  assumed.params = d.rig_check.assumed;
  const auto& c = d.rig_check;
  return fmt::format(
      "{{\"description\": {}, \"source\": {}, \"stated\": {}, \"assumed\": {}, "
      "\"changed\": {}, \"not_confirmed\": {}, \"checked\": [\"supply_pressure\", "
      "\"load_stiffness\"], \"evidence\": {{\"supply_from\": \"{}\", \"sum_rest\": {}, "
      "\"sum_open\": {}, \"load_stiffness\": {}, \"load_stiffness_error\": {}, "
      "\"constant_force\": {}, \"constant_force_error\": {}}}, \"nrmse_stated\": {}, "
      "\"nrmse_corrected\": {}, \"score\": {}, \"significance\": {}}}",
      json_string(sim::describe(d.rig)), json_string(d.rig.source), rig_values(d.rig),
      rig_values(assumed), findings_list(c.findings), findings_list(d.rig_rejected),
      c.supply_column ? "ps" : "p1+p2", number(c.sum_rest), number(c.sum_open),
      number(c.balance.K_s), number(c.balance.K_s_error), number(c.balance.constant),
      number(c.balance.constant_error), number(d.nrmse_stated), number(d.nrmse_corrected),
      number(d.rig_score), number(d.rig_significance));
}

std::string change_point_object(const ChangePoint& c) {
  return fmt::format("{{\"t_s\": {}, \"statistic\": {}, \"log_step\": {}}}", number(c.t_s),
                     number(c.statistic), number(c.step));
}

}  // namespace

std::string diagnosis_json(const Diagnosis& d) {
  std::string out = "{\n";
  out += fmt::format("  \"cause\": \"{}\",\n", d.cause);
  out += fmt::format("  \"rig\": {},\n", rig_object(d));
  out += fmt::format("  \"params\": {},\n", params_object(d.params));
  out += "  \"causes\": [";
  for (std::size_t i = 0; i < d.causes.size(); ++i) {
    const auto& cause = d.causes[i];
    out += fmt::format(
        "{}{{\"cause\": \"{}\", \"params\": {}, \"param_errors\": {}{}}}", i ? ", " : "",
        cause.effect, params_object(cause.params), errors_object(cause.params),
        cause.onset_s > 0.0
            ? fmt::format(", \"onset_s\": {}, \"onset_range_s\": [{}, {}]", number(cause.onset_s),
                          number(cause.onset_earliest_s), number(cause.onset_latest_s))
            : std::string());
  }
  out += "],\n";
  out += "  \"steps\": [";
  for (std::size_t i = 0; i < d.steps.size(); ++i) {
    const auto& s = d.steps[i];
    out += fmt::format(
        "{}{{\"effect\": \"{}\", \"nrmse\": {}, \"score\": {}, \"significance\": {}, "
        "\"accepted\": {}{}}}",
        i ? ", " : "", s.effect, number(s.nrmse), number(s.score), number(s.significance),
        s.accepted ? "true" : "false",
        s.replaces.empty() ? std::string() : fmt::format(", \"replaces\": \"{}\"", s.replaces));
  }
  out += "],\n";
  out += fmt::format("  \"nrmse_floor\": {},\n", number(d.nrmse_floor));
  if (d.change_point) {
    out += fmt::format("  \"change_point\": {},\n", change_point_object(*d.change_point));
  }
  out += "  \"onsets_tried\": [";
  for (std::size_t i = 0; i < d.onsets_tried.size(); ++i) {
    out += (i ? ", " : "") + change_point_object(d.onsets_tried[i]);
  }
  out += "],\n";
  out += fmt::format("  \"unexplained\": {},\n",
                     d.unexplained ? misfit_object(*d.unexplained) : "null");
  out += fmt::format("  \"at_bound\": {},\n", string_list(d.at_bound));
  out += fmt::format("  \"nominal_at_bound\": {},\n", string_list(d.nominal_at_bound));
  out += fmt::format("  \"drifts\": {},\n", d.drifts ? "true" : "false");
  out += "  \"drift\": [";
  for (std::size_t i = 0; i < d.drift.size(); ++i) {
    const auto& c = d.drift[i];
    out += fmt::format(
        "{}{{\"parameter\": \"{}\", \"early\": {}, \"early_error\": {}, \"late\": {}, "
        "\"late_error\": {}, \"z\": {}, \"drifts\": {}}}",
        i ? ", " : "", c.parameter, number(c.early), number(c.early_error), number(c.late),
        number(c.late_error), number(c.z), c.drifts ? "true" : "false");
  }
  out += "],\n";
  out += fmt::format("  \"transducer_noise\": {},\n",
                     channel_object({d.noise.x, d.noise.p1, d.noise.p2}));
  out += fmt::format("  \"param_errors\": {},\n", errors_object(d.params));
  const auto& c = d.calibrated;
  const auto& e = d.calibrated_errors;
  out += fmt::format("  \"calibrated\": {{\"beta\": {}, \"Kv\": {}, \"m\": {}, \"b\": {}}},\n",
                     number(c.beta), number(c.Kv), number(c.m), number(c.b));
  out +=
      fmt::format("  \"calibrated_errors\": {{\"beta\": {}, \"Kv\": {}, \"m\": {}, \"b\": {}}},\n",
                  number(e.beta), number(e.Kv), number(e.m), number(e.b));
  if (d.ripple_line) {
    out += fmt::format("  \"ripple_line\": {{\"f\": {}, \"z\": {}, \"signal\": \"{}\"}},\n",
                       number(d.ripple_line->frequency_hz), number(d.ripple_line->held_out_z),
                       d.ripple_line->from_supply_column ? "ps" : "p1+p2");
  }
  out += "  \"ranking\": [\n";
  for (std::size_t i = 0; i < d.ranking.size(); ++i) {
    const auto& r = d.ranking[i];
    out += fmt::format(
        "    {{\"effect\": \"{}\", \"score\": {}, \"significance\": {}, \"plausible\": {}, "
        "\"params\": {}}}{}\n",
        r.effect, number(r.score), number(r.significance), r.plausible ? "true" : "false",
        params_object(r.params), i + 1 < d.ranking.size() ? "," : "");
  }
  out += "  ],\n";
  out += fmt::format("  \"nrmse_before\": {},\n", number(d.nrmse_before));
  out += fmt::format("  \"nrmse_after\": {}\n", number(d.nrmse_after));
  return out + "}\n";
}

}  // namespace leakmon::model
