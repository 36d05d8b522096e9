#include "pipeline/config.hpp"

#include <algorithm>

namespace leakmon::pipeline {

const GroupConfig* group_of_driver(const DaemonConfig& config, const std::string& driver) {
  for (const auto& group : config.groups) {
    if (std::find(group.drivers.begin(), group.drivers.end(), driver) != group.drivers.end()) {
      return &group;
    }
  }
  return nullptr;
}

}  // namespace leakmon::pipeline
