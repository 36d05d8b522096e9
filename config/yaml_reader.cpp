#include "config/yaml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace leakmon::config {
namespace {

std::string mark_location(const std::string& source, const YAML::Mark& mark) {
  if (mark.is_null()) return source;
  return fmt::format("{}:{}:{}", source, mark.line + 1, mark.column + 1);
}

}  // namespace

ConfigNode::ConfigNode(YAML::Node node, std::shared_ptr<const std::string> source,
                       std::string path)
    : node_(std::move(node)), source_(std::move(source)), path_(std::move(path)) {}

ConfigNode ConfigNode::load_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(fmt::format("{}: cannot open file", path));
  std::stringstream text;
  text << in.rdbuf();
  return load_string(text.str(), path);
}

ConfigNode ConfigNode::load_string(const std::string& text, const std::string& source_name) {
  auto source = std::make_shared<const std::string>(source_name);
  try {
    YAML::Node root = YAML::Load(text);
    if (!root.IsDefined() || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    return ConfigNode(root, source, "");
  } catch (const YAML::Exception& e) {
    throw ConfigError(fmt::format("{}: {}", mark_location(source_name, e.mark), e.msg));
  }
}

std::string ConfigNode::location() const { return mark_location(*source_, node_.Mark()); }

void ConfigNode::fail(std::string_view message) const {
  if (path_.empty()) throw ConfigError(fmt::format("{}: {}", location(), message));
  throw ConfigError(fmt::format("{}: {}: {}", location(), path_, message));
}

std::string ConfigNode::child_path(std::string_view key) const {
  return path_.empty() ? std::string(key) : fmt::format("{}.{}", path_, key);
}

void ConfigNode::expect_keys(std::initializer_list<std::string_view> allowed) const {
  expect_keys(std::vector<std::string>(allowed.begin(), allowed.end()));
}

void ConfigNode::expect_keys(const std::vector<std::string>& allowed) const {
  if (is_null()) return;
  if (!node_.IsMap()) fail("expected a mapping of keys to values");
  for (const auto& kv : node_) {
    const auto key = kv.first.as<std::string>();
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      ConfigNode key_node(kv.first, source_, child_path(key));
      key_node.fail(fmt::format("unknown key '{}' (allowed: {})", key, fmt::join(allowed, ", ")));
    }
  }
}

bool ConfigNode::has(std::string_view key) const {
  return node_.IsMap() && node_[std::string(key)].IsDefined() && !node_[std::string(key)].IsNull();
}

ConfigNode ConfigNode::at(std::string_view key) const {
  if (!node_.IsMap()) fail(fmt::format("expected a mapping containing '{}'", key));
  YAML::Node child = node_[std::string(key)];
  if (!child.IsDefined() || child.IsNull()) fail(fmt::format("missing required key '{}'", key));
  return ConfigNode(child, source_, child_path(key));
}

std::optional<ConfigNode> ConfigNode::find(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return at(key);
}

std::vector<ConfigNode> ConfigNode::items() const {
  if (!node_.IsSequence()) fail("expected a list");
  std::vector<ConfigNode> out;
  std::size_t i = 0;
  for (const auto& item : node_) {
    out.push_back(ConfigNode(item, source_, fmt::format("{}[{}]", path_, i++)));
  }
  return out;
}

std::vector<std::pair<std::string, ConfigNode>> ConfigNode::entries() const {
  if (!node_.IsMap()) fail("expected a mapping of keys to values");
  std::vector<std::pair<std::string, ConfigNode>> out;
  for (const auto& kv : node_) {
    auto key = kv.first.as<std::string>();
    out.emplace_back(key, ConfigNode(kv.second, source_, child_path(key)));
  }
  return out;
}

std::string ConfigNode::as_string() const {
  if (!node_.IsScalar()) fail("expected a text value");
  return node_.Scalar();
}

double ConfigNode::as_double() const {
  if (!node_.IsScalar()) fail("expected a number");
  const std::string& s = node_.Scalar();
  double value = 0;
  const char* first = s.data();
  if (!s.empty() && s.front() == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(value)) {
    fail(fmt::format("expected a finite number, got '{}'", s));
  }
  return value;
}

long long ConfigNode::as_int() const {
  if (!node_.IsScalar()) fail("expected an integer");
  const std::string& s = node_.Scalar();
  long long value = 0;
  const char* first = s.data();
  if (!s.empty() && s.front() == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size()) {
    fail(fmt::format("expected an integer, got '{}'", s));
  }
  return value;
}

bool ConfigNode::as_bool() const {
  if (!node_.IsScalar()) fail("expected true or false");
  const std::string& s = node_.Scalar();
  if (s == "true" || s == "yes" || s == "on") return true;
  if (s == "false" || s == "no" || s == "off") return false;
  fail(fmt::format("expected true or false, got '{}'", s));
}

std::string ConfigNode::get_string(std::string_view key, std::string_view fallback) const {
  auto child = find(key);
  return child ? child->as_string() : std::string(fallback);
}

std::string ConfigNode::get_choice(std::string_view key,
                                   std::initializer_list<std::string_view> choices,
                                   std::string_view fallback) const {
  auto child = find(key);
  if (!child) return std::string(fallback);
  std::string value = child->as_string();
  if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
    child->fail(fmt::format("'{}' is not one of: {}", value, fmt::join(choices, ", ")));
  }
  return value;
}

double ConfigNode::check_range(double value, double lo, double hi) const {
  if (value < lo || value > hi) {
    fail(fmt::format("value {} is out of range [{}, {}]", value, lo, hi));
  }
  return value;
}

double ConfigNode::get_double(std::string_view key, double lo, double hi) const {
  ConfigNode child = at(key);
  return child.check_range(child.as_double(), lo, hi);
}

double ConfigNode::get_double(std::string_view key, double fallback, double lo, double hi) const {
  auto child = find(key);
  if (!child) return fallback;
  return child->check_range(child->as_double(), lo, hi);
}

long long ConfigNode::get_int(std::string_view key, long long lo, long long hi) const {
  ConfigNode child = at(key);
  long long v = child.as_int();
  if (v < lo || v > hi) child.fail(fmt::format("value {} is out of range [{}, {}]", v, lo, hi));
  return v;
}

long long ConfigNode::get_int(std::string_view key, long long fallback, long long lo,
                              long long hi) const {
  if (!has(key)) return fallback;
  return get_int(key, lo, hi);
}

bool ConfigNode::get_bool(std::string_view key, bool fallback) const {
  auto child = find(key);
  return child ? child->as_bool() : fallback;
}

}  // namespace leakmon::config
