#include "pipeline/config.hpp"

#include <algorithm>

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

const GroupConfig* group_of_driver(const DaemonConfig& config, const std::string& driver) {
  for (const auto& group : config.groups) {
    if (std::find(group.drivers.begin(), group.drivers.end(), driver) != group.drivers.end()) {
      return &group;
    }
  }
  return nullptr;
}

}  // namespace leakmon::pipeline
