#include "config/paths.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace leakmon::config {

std::string resolve_path(const ConfigNode& node, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(node.source()).parent_path() / path).lexically_normal().string();
}

std::string secret_path(const ConfigNode& field) {
  const std::string name = field.as_string();
  if (name.empty()) field.fail("the file name must not be empty");
  if (std::filesystem::path(name).is_absolute()) return name;
  if (const char* dir = std::getenv("CREDENTIALS_DIRECTORY"); dir != nullptr && *dir != '\0') {
    return (std::filesystem::path(dir) / name).lexically_normal().string();
  }
  return resolve_path(field, name);
}

std::string read_secret(const ConfigNode& field) {
  const std::string path = secret_path(field);
  constexpr std::size_t kMaxBytes = 64 * 1024;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    field.fail(fmt::format("'{}' is a directory, not a file holding the secret", path));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) field.fail(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
  std::ostringstream text;
  text << in.rdbuf();
  std::string secret = text.str();
  if (secret.size() > kMaxBytes) field.fail(fmt::format("'{}' is larger than 64 KiB", path));
  if (!secret.empty() && secret.back() == '\n') secret.pop_back();
  if (!secret.empty() && secret.back() == '\r') secret.pop_back();
  if (secret.empty()) field.fail(fmt::format("'{}' is empty", path));
  return secret;
}

std::string default_state_directory() {
  if (const char* env = std::getenv("STATE_DIRECTORY"); env != nullptr && *env != '\0') {
    const std::string list(env);
    return list.substr(0, list.find(':'));
  }
  return "/var/lib/leakmon";
}

}  // namespace leakmon::config
