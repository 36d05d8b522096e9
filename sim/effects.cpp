#include "sim/effects.hpp"

#include <array>
#include <string>
#include <utility>

namespace leakmon::sim {
namespace {

constexpr std::array<std::string_view, 11> kEffectNames = {
    "internal_leakage", "external_leakage", "coulomb_friction", "entrained_air",
    "valve_overlap",    "valve_bias",       "spool_lag",        "supply_ripple",
    "supply_droop",     "sensor_offset",    "sensor_lag"};

// A table of one effect's parameters: name -> member, so that describe() and enable() cannot
// drift apart.
template <typename Effect>
struct NumberField {
  std::string_view name;
  double Effect::*member;
};

[[noreturn]] void fail(std::string_view effect, std::string_view message) {
  throw EffectError(std::string(effect) + ": " + std::string(message));
}

double number(std::string_view effect, const EffectParameter& param) {
  if (const double* value = std::get_if<double>(&param.value)) return *value;
  fail(effect, "parameter '" + param.name + "' must be a number");
}

PressureChannel channel(std::string_view effect, const EffectParameter& param) {
  const std::string* text = std::get_if<std::string>(&param.value);
  if (text && *text == "p1") return PressureChannel::p1;
  if (text && *text == "p2") return PressureChannel::p2;
  fail(effect, "parameter 'channel' must be \"p1\" or \"p2\"");
}

template <typename Effect, std::size_t N>
void assign(std::string_view effect, Effect& target,
            const std::array<NumberField<Effect>, N>& fields,
            std::span<const EffectParameter> params) {
  for (const auto& param : params) {
    bool known = false;
    for (const auto& field : fields) {
      if (field.name != param.name) continue;
      target.*field.member = number(effect, param);
      known = true;
    }
    if (!known) fail(effect, "unknown parameter '" + param.name + "'");
  }
}

}  // namespace

std::string_view to_string(PressureChannel channel) {
  return channel == PressureChannel::p1 ? "p1" : "p2";
}

std::span<const std::string_view> Effects::names() { return kEffectNames; }

std::vector<EffectDescription> Effects::describe() const {
  std::vector<EffectDescription> out;
  const auto num = [](std::string name, double value) {
    return EffectParameter{std::move(name), value};
  };
  if (internal_leakage) {
    out.push_back({"internal_leakage",
                   {num("C_L", internal_leakage->C_L), num("onset_s", internal_leakage->onset_s),
                    num("ramp_s", internal_leakage->ramp_s)}});
  }
  if (external_leakage) {
    EffectDescription ext{"external_leakage",
                          {num("C_E", external_leakage->C_E),
                           num("chamber", static_cast<double>(external_leakage->chamber))}};
    // Listed only when set, so that a leak present from the start reads as MODEL.md's table.
    if (external_leakage->onset_s != 0.0)
      ext.params.push_back(num("onset_s", external_leakage->onset_s));
    if (external_leakage->ramp_s != 0.0)
      ext.params.push_back(num("ramp_s", external_leakage->ramp_s));
    out.push_back(std::move(ext));
  }
  if (coulomb_friction) out.push_back({"coulomb_friction", {num("F_C", coulomb_friction->F_C)}});
  if (entrained_air) out.push_back({"entrained_air", {num("alpha", entrained_air->alpha)}});
  if (valve_overlap) out.push_back({"valve_overlap", {num("d", valve_overlap->d)}});
  if (valve_bias) out.push_back({"valve_bias", {num("u0", valve_bias->u0)}});
  if (spool_lag) out.push_back({"spool_lag", {num("tau", spool_lag->tau)}});
  if (supply_ripple) {
    out.push_back({"supply_ripple", {num("dP", supply_ripple->dP), num("f", supply_ripple->f)}});
  }
  if (supply_droop) out.push_back({"supply_droop", {num("R_s", supply_droop->R_s)}});
  if (sensor_offset) {
    out.push_back({"sensor_offset",
                   {num("offset", sensor_offset->offset),
                    {"channel", std::string(to_string(sensor_offset->channel))}}});
  }
  if (sensor_lag) {
    out.push_back({"sensor_lag",
                   {num("tau_s", sensor_lag->tau_s),
                    {"channel", std::string(to_string(sensor_lag->channel))}}});
  }
  return out;
}

void Effects::enable(std::string_view name, std::span<const EffectParameter> params) {
  // All or nothing: a bad parameter leaves the effects as they were.
  Effects updated = *this;
  updated.enable_unchecked(name, params);
  *this = std::move(updated);
}

void Effects::enable_unchecked(std::string_view name, std::span<const EffectParameter> params) {
  if (name == "internal_leakage") {
    internal_leakage.emplace();
    assign<InternalLeakage, 3>(name, *internal_leakage,
                               {{{"C_L", &InternalLeakage::C_L},
                                 {"onset_s", &InternalLeakage::onset_s},
                                 {"ramp_s", &InternalLeakage::ramp_s}}},
                               params);
  } else if (name == "external_leakage") {
    external_leakage.emplace();
    for (const auto& param : params) {
      if (param.name == "C_E") {
        external_leakage->C_E = number(name, param);
      } else if (param.name == "chamber") {
        const double chamber = number(name, param);
        if (chamber != 1.0 && chamber != 2.0) fail(name, "parameter 'chamber' must be 1 or 2");
        external_leakage->chamber = static_cast<int>(chamber);
      } else if (param.name == "onset_s") {
        external_leakage->onset_s = number(name, param);
      } else if (param.name == "ramp_s") {
        external_leakage->ramp_s = number(name, param);
      } else {
        fail(name, "unknown parameter '" + param.name + "'");
      }
    }
  } else if (name == "coulomb_friction") {
    coulomb_friction.emplace();
    assign<CoulombFriction, 1>(name, *coulomb_friction, {{{"F_C", &CoulombFriction::F_C}}}, params);
  } else if (name == "entrained_air") {
    entrained_air.emplace();
    assign<EntrainedAir, 1>(name, *entrained_air, {{{"alpha", &EntrainedAir::alpha}}}, params);
  } else if (name == "valve_overlap") {
    valve_overlap.emplace();
    assign<ValveOverlap, 1>(name, *valve_overlap, {{{"d", &ValveOverlap::d}}}, params);
  } else if (name == "valve_bias") {
    valve_bias.emplace();
    assign<ValveBias, 1>(name, *valve_bias, {{{"u0", &ValveBias::u0}}}, params);
  } else if (name == "spool_lag") {
    spool_lag.emplace();
    assign<SpoolLag, 1>(name, *spool_lag, {{{"tau", &SpoolLag::tau}}}, params);
  } else if (name == "supply_ripple") {
    supply_ripple.emplace();
    assign<SupplyRipple, 2>(name, *supply_ripple,
                            {{{"dP", &SupplyRipple::dP}, {"f", &SupplyRipple::f}}}, params);
  } else if (name == "supply_droop") {
    supply_droop.emplace();
    assign<SupplyDroop, 1>(name, *supply_droop, {{{"R_s", &SupplyDroop::R_s}}}, params);
  } else if (name == "sensor_offset" || name == "sensor_lag") {
    PressureChannel which = PressureChannel::p1;
    std::vector<EffectParameter> numbers;
    for (const auto& param : params) {
      if (param.name == "channel") {
        which = channel(name, param);
      } else {
        numbers.push_back(param);
      }
    }
    if (name == "sensor_offset") {
      sensor_offset.emplace();
      sensor_offset->channel = which;
      assign<SensorOffset, 1>(name, *sensor_offset, {{{"offset", &SensorOffset::offset}}}, numbers);
    } else {
      sensor_lag.emplace();
      sensor_lag->channel = which;
      assign<SensorLag, 1>(name, *sensor_lag, {{{"tau_s", &SensorLag::tau_s}}}, numbers);
    }
  } else {
    fail(name, "unknown effect (MODEL.md's effect library names it)");
  }
}

void Effects::disable(std::string_view name) {
  if (name == "internal_leakage")
    internal_leakage.reset();
  else if (name == "external_leakage")
    external_leakage.reset();
  else if (name == "coulomb_friction")
    coulomb_friction.reset();
  else if (name == "entrained_air")
    entrained_air.reset();
  else if (name == "valve_overlap")
    valve_overlap.reset();
  else if (name == "valve_bias")
    valve_bias.reset();
  else if (name == "spool_lag")
    spool_lag.reset();
  else if (name == "supply_ripple")
    supply_ripple.reset();
  else if (name == "supply_droop")
    supply_droop.reset();
  else if (name == "sensor_offset")
    sensor_offset.reset();
  else if (name == "sensor_lag")
    sensor_lag.reset();
  else
    fail(name, "unknown effect");
}

}  // namespace leakmon::sim
