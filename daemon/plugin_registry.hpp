// The one lookup behind the driver and output registries: a fixed table of `type:` names and
// the factories that build a plug-in from its YAML mapping.
#pragma once

#include <fmt/format.h>

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "config/yaml_reader.hpp"

namespace leakmon::daemon {

template <class Product>
struct PluginType {
  // Builds the plug-in from its mapping (including `name:` and `type:`); validates every field
  // with ConfigNode::fail (file:line:column) and opens no device.
  using Factory = std::unique_ptr<Product> (*)(const config::ConfigNode& node);

  std::string_view type;
  Factory factory;
};

// The plug-in for `node.type`, failing at the `type:` field, with the known names, when no
// entry has that name. `kind` names the table in that message ("driver", "output").
template <class Product>
std::unique_ptr<Product> make_plugin(std::span<const PluginType<Product>> types,
                                     std::string_view kind, const config::ConfigNode& node) {
  const auto type_node = node.at("type");
  const std::string type = type_node.as_string();
  for (const auto& entry : types) {
    if (entry.type == type) return entry.factory(node);
  }
  std::vector<std::string_view> known;
  for (const auto& entry : types) known.push_back(entry.type);
  type_node.fail(
      fmt::format("unknown {} type '{}' (known: {})", kind, type, fmt::join(known, ", ")));
}

}  // namespace leakmon::daemon
