#include "model/rig_source.hpp"

#include <fmt/format.h>

#include "config/yaml_reader.hpp"

namespace leakmon::model {

sim::RigDescription load_actuator_rig(const std::string& config_path, const std::string& actuator) {
  const auto root = config::ConfigNode::load_file(config_path);
  if (!root.is_map()) root.fail("a daemon configuration must be a mapping with 'actuators:'");
  const auto actuators = root.at("actuators");
  if (!actuators.is_sequence()) {
    actuators.fail("'actuators' must be a list of actuators, each with a 'name'");
  }
  std::string known;
  for (const auto& node : actuators.items()) {
    if (!node.is_map()) node.fail("an actuator must be a mapping with a 'name'");
    const std::string name = node.get_string("name");
    if (name == actuator) {
      if (const auto rig = node.find("rig")) return sim::read_rig(*rig);
      return sim::RigDescription::paper();
    }
    known += (known.empty() ? "" : ", ") + config::printable(name);
  }
  actuators.fail(fmt::format("no actuator named '{}' (known: {})", config::printable(actuator),
                             known.empty() ? "none" : known));
}

}  // namespace leakmon::model
