#include "detect/rig_options.hpp"

#include <array>

namespace leakmon::detect {
namespace {

constexpr std::string_view kSupply[] = {"supply_pressure"};
constexpr std::string_view kTank[] = {"tank_pressure"};
constexpr std::string_view kCommand[] = {"command_full_scale"};
constexpr std::string_view kValve[] = {"valve_coefficient", "valve_rated_flow"};
constexpr std::string_view kArea[] = {"bore", "rod"};
constexpr std::string_view kOil[] = {"oil_grade", "oil_viscosity_40", "oil_viscosity_100"};

constexpr std::array kOptions = {
    RigOption{"supply_pressure", kSupply},     RigOption{"tank_pressure", kTank},
    RigOption{"command_full_scale", kCommand}, RigOption{"valve_coefficient", kValve},
    RigOption{"piston_area", kArea},           RigOption{"oil_grade", kOil},
    RigOption{"oil_viscosity_40", kOil},       RigOption{"oil_viscosity_100", kOil},
};

}  // namespace

std::span<const RigOption> rig_options() { return kOptions; }

std::vector<RigRestatement> restated_rig_values(const config::ConfigNode& options,
                                                const sim::RigDescription& rig) {
  std::vector<RigRestatement> out;
  if (!options.is_map()) return out;
  for (const RigOption& spec : kOptions) {
    const auto node = options.find(spec.option);
    if (!node) continue;
    RigRestatement restated{*node, {}};
    for (const auto key : spec.keys) {
      if (rig.states(key)) restated.rig_keys.emplace_back(key);
    }
    if (!restated.rig_keys.empty()) out.push_back(std::move(restated));
  }
  return out;
}

}  // namespace leakmon::detect
