// Fuzzes the configuration reader (config/yaml_reader.*): arbitrary bytes as a YAML
// configuration, then every node visited the way the daemon's schema code visits them (keys
// checked, scalars converted, lists and mappings walked). Invariants: the only error is a
// ConfigError (never a yaml-cpp exception or a crash), its message starts with the file name and
// is valid UTF-8 without control characters (configuration content is escaped before it reaches
// a terminal or the log), and printable() keeps that promise for any text.
// fuzz-sources: config/yaml_reader.cpp
// fuzz-libs: -lyaml-cpp -lfmt
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "config/yaml_reader.hpp"

using leakmon::config::ConfigError;
using leakmon::config::ConfigNode;

namespace {

void check_clean(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    unsigned code = 0;
    const std::size_t length = leakmon::config::utf8_sequence(text, i, code);
    if (length == 0) __builtin_trap();                                   // invalid UTF-8 escaped
    if (code < 0x20 || (code >= 0x7f && code < 0xa0)) __builtin_trap();  // raw control
    i += length;
  }
}

void visit(const ConfigNode& node, int depth) {
  if (depth > 64) return;
  try {
    if (node.is_map()) {
      node.expect_keys({"drivers", "name", "type", "port", "seed"});
    }
  } catch (const ConfigError&) {
  }
  try {
    if (node.is_map()) {
      for (const auto& [key, child] : node.entries()) visit(child, depth + 1);
      (void)node.get_string("name", "x");
      (void)node.get_double("port", 0.0, -1e9, 1e9);
      (void)node.get_int("seed", 0, -5, 5);
      (void)node.get_bool("on", false);
    } else if (node.is_sequence()) {
      for (const auto& item : node.items()) visit(item, depth + 1);
    } else if (node.is_scalar()) {
      (void)node.as_string();
      (void)node.as_double();
    }
  } catch (const ConfigError& e) {
    const std::string message = e.what();
    if (!message.starts_with("fuzz.yaml")) __builtin_trap();
    check_clean(message);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  check_clean(leakmon::config::printable(text, 1 << 20));
  try {
    const ConfigNode root = ConfigNode::load_string(text, "fuzz.yaml");
    visit(root, 0);
  } catch (const ConfigError& e) {
    const std::string message = e.what();
    if (!message.starts_with("fuzz.yaml")) __builtin_trap();
    check_clean(message);
  }
  return 0;
}
