#include "sim/rig_description.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace leakmon::sim {

namespace {

// MODEL.md "Other rigs", in its order. Ranges: physically meaningful, wider than the table's
// typical ones.
constexpr std::array kKeys = {
    RigKey{"bore", "D", "m", 5e-3, 1.0, "piston bore"},
    RigKey{"rod", "d", "m", 0.0, 1.0, "rod diameter (double rod)"},
    RigKey{"stroke", "L", "m", 1e-3, 10.0, "stroke"},
    RigKey{"dead_volume", "V_dead", "m^3", 1e-7, 0.1, "dead volume per side"},
    RigKey{"line_volume", "V_line", "m^3", 0.0, 0.1, "valve-to-cylinder line volume per side"},
    RigKey{"supply_pressure", "ps", "Pa", 1e5, 1e8, "supply pressure"},
    RigKey{"tank_pressure", "pt", "Pa", 0.0, 1e7, "tank pressure"},
    RigKey{"bulk_modulus", "beta", "Pa", 1e7, 1e10, "effective bulk modulus"},
    RigKey{"moving_mass", "m", "kg", 0.1, 1e5, "moving mass"},
    RigKey{"viscous_friction", "b", "N s/m", 0.0, 1e6, "viscous friction"},
    RigKey{"load_stiffness", "K_s", "N/m", 0.0, 1e9, "load spring"},
    RigKey{"valve_coefficient", "Kv", "m^3/(s sqrt(Pa))", 1e-10, 1e-3, "valve coefficient"},
    RigKey{"valve_rated_flow", "", "m^3/s", 1e-7, 1.0, "valve rated flow (data sheet)"},
    RigKey{"valve_rated_pressure_drop", "", "Pa", 1e4, 1e8,
           "valve rated pressure drop, total over both lands (data sheet)"},
    RigKey{"valve_time_constant", "tau", "s", 1e-4, 1.0, "spool time constant"},
    RigKey{"command_full_scale", "u_max", "V", 0.1, 100.0, "valve command full scale"},
    RigKey{"null_leakage", "C_n", "m^3/(s Pa)", 0.0, 1e-9, "valve null leakage per land"},
    RigKey{"oil_grade", "", "", 32.0, 68.0, "ISO VG grade: 32, 46 or 68"},
    RigKey{"oil_viscosity_40", "", "mm^2/s", 1.0, 1e4, "oil viscosity at 40 degC (data sheet)"},
    RigKey{"oil_viscosity_100", "", "mm^2/s", 0.5, 1e3, "oil viscosity at 100 degC (data sheet)"},
};

double* parameter_of(Parameters& p, std::string_view symbol) {
  if (symbol == "D") return &p.D;
  if (symbol == "d") return &p.d;
  if (symbol == "L") return &p.L;
  if (symbol == "V_dead") return &p.V_dead;
  if (symbol == "V_line") return &p.V_line;
  if (symbol == "ps") return &p.ps;
  if (symbol == "pt") return &p.pt;
  if (symbol == "beta") return &p.beta;
  if (symbol == "m") return &p.m;
  if (symbol == "b") return &p.b;
  if (symbol == "K_s") return &p.K_s;
  if (symbol == "Kv") return &p.Kv;
  if (symbol == "tau") return &p.tau;
  if (symbol == "u_max") return &p.u_max;
  if (symbol == "C_n") return &p.C_n;
  return nullptr;
}

const RigKey* key_named(std::string_view key) {
  const auto it =
      std::find_if(kKeys.begin(), kKeys.end(), [&](const RigKey& k) { return k.key == key; });
  return it == kKeys.end() ? nullptr : &*it;
}

std::string allowed_keys() {
  std::string list;
  for (const auto& k : kKeys) {
    if (!list.empty()) list += ", ";
    list += k.key;
  }
  return list;
}

// Kv = Q_rated / sqrt(dp_rated / 2): the rated drop is over both lands, each sees half.
double kv_from_rating(double flow, double drop) { return flow / std::sqrt(drop / 2.0); }

// Engineering notation for describe(): mm for lengths, MPa, kN/m, l/min.
std::string quantity(const RigDescription& rig, const RigKey& key) {
  const double v = *rig_value(rig, key.key);
  const std::string_view k = key.key;
  if (k == "bore" || k == "rod" || k == "stroke") return fmt::format("{} {:.4g} mm", k, v * 1e3);
  if (k == "supply_pressure" || k == "tank_pressure" || k == "valve_rated_pressure_drop") {
    return fmt::format("{} {:.4g} MPa", k, v * 1e-6);
  }
  if (k == "bulk_modulus") return fmt::format("{} {:.4g} GPa", k, v * 1e-9);
  if (k == "load_stiffness") return fmt::format("{} {:.4g} kN/m", k, v * 1e-3);
  if (k == "valve_rated_flow") return fmt::format("{} {:.4g} l/min", k, v * 60000.0);
  if (k == "valve_time_constant") return fmt::format("{} {:.4g} ms", k, v * 1e3);
  if (k == "oil_grade") return fmt::format("oil {}", rig.oil.name());
  if (key.unit.empty()) return fmt::format("{} {:.4g}", k, v);
  return fmt::format("{} {:.4g} {}", k, v, key.unit);
}

}  // namespace

std::span<const RigKey> rig_keys() { return kKeys; }

bool RigDescription::states(std::string_view key) const {
  return std::find(stated.begin(), stated.end(), key) != stated.end();
}

bool RigDescription::states_symbol(std::string_view symbol) const {
  if (symbol == "Kv") {
    return states("valve_coefficient") || states("valve_rated_flow");
  }
  if (symbol == "oil") return states("oil_grade") || states("oil_viscosity_40");
  for (const auto& key : kKeys) {
    if (key.symbol == symbol && states(key.key)) return true;
  }
  return false;
}

RigDescription read_rig(const config::ConfigNode& node) {
  RigDescription rig;
  rig.source = node.location();
  if (node.is_null()) return rig;
  if (!node.is_map())
    node.fail("the rig's description must be a mapping of keys (" + allowed_keys() + ")");
  for (const auto& [key, value] : node.entries()) {
    const RigKey* spec = key_named(key);
    if (spec == nullptr) {
      value.fail(
          fmt::format("unknown rig key '{}' (known: {})", config::printable(key), allowed_keys()));
    }
    rig.stated.push_back(key);
    if (spec->symbol.empty()) continue;  // valve rating and oil: below
    *parameter_of(rig.params, spec->symbol) =
        value.check_range(value.as_double(), spec->lo, spec->hi);
  }

  const auto flow = node.find("valve_rated_flow");
  const auto drop = node.find("valve_rated_pressure_drop");
  if (flow.has_value() != drop.has_value()) {
    (flow ? *flow : *drop)
        .fail(
            "give both valve_rated_flow and valve_rated_pressure_drop (the data sheet's rated "
            "flow at its rated total pressure drop), or valve_coefficient");
  }
  if (flow) {
    if (const auto kv = node.find("valve_coefficient")) {
      kv->fail("the valve is given twice: valve_coefficient and valve_rated_flow; give one");
    }
    const auto& q = *key_named("valve_rated_flow");
    const auto& p = *key_named("valve_rated_pressure_drop");
    rig.valve_rated_pressure_drop = drop->check_range(drop->as_double(), p.lo, p.hi);
    rig.params.Kv = kv_from_rating(flow->check_range(flow->as_double(), q.lo, q.hi),
                                   rig.valve_rated_pressure_drop);
  }

  const auto grade = node.find("oil_grade");
  const auto nu40 = node.find("oil_viscosity_40");
  const auto nu100 = node.find("oil_viscosity_100");
  if (grade && (nu40 || nu100)) {
    grade->fail("the oil is given twice: give oil_grade or oil_viscosity_40 and _100");
  }
  if (grade) {
    const auto oil = Oil::iso_vg(static_cast<int>(grade->as_int()));
    if (!oil) grade->fail("oil_grade must be 32, 46 or 68 (or give oil_viscosity_40 and _100)");
    rig.oil = *oil;
  } else if (nu40 || nu100) {
    if (!nu40 || !nu100) {
      (nu40 ? *nu40 : *nu100).fail("give both oil_viscosity_40 and oil_viscosity_100");
    }
    const auto& k40 = *key_named("oil_viscosity_40");
    const auto& k100 = *key_named("oil_viscosity_100");
    const double a = nu40->check_range(nu40->as_double(), k40.lo, k40.hi);
    const double b = nu100->check_range(nu100->as_double(), k100.lo, k100.hi);
    if (!(b < a)) nu100->fail("oil_viscosity_100 must be below oil_viscosity_40");
    rig.oil = Oil(a, b);
  }

  if (!(rig.params.d < rig.params.D)) {
    const auto at = node.find("rod") ? node.at("rod") : node.at("bore");
    at.fail(fmt::format("the rod ({:.4g} mm) must be thinner than the bore ({:.4g} mm)",
                        rig.params.d * 1e3, rig.params.D * 1e3));
  }
  if (!(rig.params.pt < rig.params.ps)) {
    const auto at =
        node.find("tank_pressure") ? node.at("tank_pressure") : node.at("supply_pressure");
    at.fail("the tank pressure must be below the supply pressure");
  }
  return rig;
}

RigDescription load_rig_file(const std::string& path) {
  const auto root = config::ConfigNode::load_file(path);
  root.expect_keys({"rig"});
  return read_rig(root.at("rig"));
}

std::optional<double> rig_value(const RigDescription& rig, std::string_view key) {
  const RigKey* spec = key_named(key);
  if (spec == nullptr) return std::nullopt;
  if (!spec->symbol.empty()) {
    auto params = rig.params;
    return *parameter_of(params, spec->symbol);
  }
  if (key == "valve_rated_pressure_drop") return rig.valve_rated_pressure_drop;
  if (key == "valve_rated_flow") {
    return rig.params.Kv * std::sqrt(rig.valve_rated_pressure_drop / 2.0);
  }
  if (key == "oil_viscosity_40") return rig.oil.nu40();
  if (key == "oil_viscosity_100") return rig.oil.nu100();
  for (int grade : {32, 46, 68}) {  // oil_grade
    const auto oil = Oil::iso_vg(grade);
    if (oil->nu40() == rig.oil.nu40() && oil->nu100() == rig.oil.nu100()) return grade;
  }
  return std::nullopt;
}

RigDescription with_value(const RigDescription& rig, std::string_view key, double value) {
  const RigKey* spec = key_named(key);
  RigDescription out = rig;
  if (spec != nullptr && !spec->symbol.empty()) {
    *parameter_of(out.params, spec->symbol) = value;
  } else if (key == "valve_rated_flow") {
    out.params.Kv = kv_from_rating(value, out.valve_rated_pressure_drop);
  } else {
    throw std::invalid_argument(fmt::format("rig key '{}' cannot be set to a number", key));
  }
  if (!out.states(key)) out.stated.emplace_back(key);
  return out;
}

std::string describe(const RigDescription& rig) {
  if (rig.nominal()) return "the paper's rig (MODEL.md nominal)";
  std::string text;
  for (const auto& key : kKeys) {
    if (!rig.states(key.key) || key.key == "valve_rated_pressure_drop") continue;
    if (key.key == "oil_viscosity_100") continue;
    std::string part;
    if (key.key == "valve_rated_flow") {
      part = fmt::format("valve {:.4g} l/min at {:.4g} MPa",
                         *rig_value(rig, "valve_rated_flow") * 60000.0,
                         rig.valve_rated_pressure_drop * 1e-6);
    } else if (key.key == "oil_viscosity_40") {
      part = fmt::format("oil {:.4g}/{:.4g} mm^2/s", rig.oil.nu40(), rig.oil.nu100());
    } else {
      part = quantity(rig, key);
    }
    if (!text.empty()) text += ", ";
    text += part;
  }
  return text;
}

std::string rig_file_text(const RigDescription& rig) {
  std::string out = fmt::format("# {}\nrig:\n", describe(rig));
  for (const auto& key : rig_keys()) {
    if (key.symbol.empty()) continue;  // the valve's rating and the oil: below
    out += fmt::format("  {}: {:.9g}\n", key.key, *rig_value(rig, key.key));
  }
  if (const auto grade = rig_value(rig, "oil_grade")) {
    out += fmt::format("  oil_grade: {:g}\n", *grade);
  } else {
    out += fmt::format("  oil_viscosity_40: {:.9g}\n  oil_viscosity_100: {:.9g}\n", rig.oil.nu40(),
                       rig.oil.nu100());
  }
  return out;
}

}  // namespace leakmon::sim
