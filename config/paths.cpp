#include "config/paths.hpp"

#include <cstdlib>
#include <filesystem>

namespace leakmon::config {

std::string resolve_path(const ConfigNode& node, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(node.source()).parent_path() / path).lexically_normal().string();
}

std::string default_state_directory() {
  if (const char* env = std::getenv("STATE_DIRECTORY"); env != nullptr && *env != '\0') {
    const std::string list(env);
    return list.substr(0, list.find(':'));
  }
  return "/var/lib/leakmon";
}

}  // namespace leakmon::config
