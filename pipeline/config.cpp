#include "pipeline/config.hpp"

#include <algorithm>

#include "sim/sensors.hpp"

namespace leakmon::pipeline {

capture::ByRole<detect::TransducerSpec> default_transducers() {
  capture::ByRole<detect::TransducerSpec> specs;
  specs[capture::Role::p1] = detect::TransducerSpec::pressure();
  specs[capture::Role::p2] = detect::TransducerSpec::pressure();
  specs[capture::Role::x] = detect::TransducerSpec::position();
  return specs;
}

capture::ByRole<bool> ActuatorConfig::acquired() const {
  capture::ByRole<bool> roles;
  for (const capture::Role role : capture::kRoles) roles[role] = channels[role].present();
  return roles;
}

detect::AvailableSignals available_signals(const capture::ByRole<bool>& acquired) {
  using capture::Role;
  detect::AvailableSignals signals;
  signals.p1 = acquired[Role::p1];
  signals.p2 = acquired[Role::p2];
  signals.u = acquired[Role::u];
  signals.x = acquired[Role::x];
  return signals;
}

namespace {

// The pressure transducers a rig that states its supply is fitted with: 12 bit over the usual
// range above its supply (sim::sensors_for: MODEL.md's 0-20.7 MPa for the paper's 17.2 MPa), as
// the simulator assumes for it.
detect::TransducerSpec pressure_transducer_for(const sim::RigDescription& rig) {
  detect::TransducerSpec spec = detect::TransducerSpec::pressure();
  if (!rig.states("supply_pressure")) return spec;
  spec.max = sim::sensors_for(rig.params).pressure_full_scale;
  spec.resolution = spec.max / 4096.0;
  return spec;
}

}  // namespace

void apply_rig(ActuatorConfig& actuator, sim::RigDescription rig) {
  actuator.rig = std::move(rig);
  actuator.transducers[capture::Role::p1] = actuator.transducers[capture::Role::p2] =
      pressure_transducer_for(actuator.rig);
}

const GroupConfig* group_of_driver(const DaemonConfig& config, const std::string& driver) {
  for (const auto& group : config.groups) {
    if (std::find(group.drivers.begin(), group.drivers.end(), driver) != group.drivers.end()) {
      return &group;
    }
  }
  return nullptr;
}

}  // namespace leakmon::pipeline
