#include "model/result_json.hpp"

#include <fmt/format.h>

#include <cmath>

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
    if (p.is_text() || p.name == "chamber") continue;
    out += fmt::format("{}\"{}\": {}", first ? "" : ", ", p.name, number(p.error));
    first = false;
  }
  return out + "}";
}

}  // namespace

std::string diagnosis_json(const Diagnosis& d) {
  std::string out = "{\n";
  out += fmt::format("  \"cause\": \"{}\",\n", d.cause);
  out += fmt::format("  \"params\": {},\n", params_object(d.params));
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
