// Reading YAML configuration with errors an operator can act on: every problem is reported as
// `file:line:column: message`, unknown keys are errors (a typo must not silently fall back to a
// default), and numeric fields are range-checked where they are read.
#pragma once

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::config {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `text` made safe for a terminal, a log and a JSON string: control characters (ESC included)
// become `\xNN`, bytes that are not valid UTF-8 become U+FFFD, and anything longer than
// `max_bytes` is cut with "...". Configuration content reaches messages only through this.
std::string printable(std::string_view text, std::size_t max_bytes = 200);

// The length of the valid UTF-8 sequence at text[i] (1 to 4) with its code point in `code`, or
// 0 when the bytes there are not valid UTF-8 (stray continuation, overlong form, surrogate,
// beyond U+10FFFF, cut short).
std::size_t utf8_sequence(std::string_view text, std::size_t i, unsigned& code);

// Throws ConfigError at the second occurrence of a key in any mapping of `text` (yaml-cpp's
// node API keeps one of them silently), naming both places. Parse errors are left to the loader.
void reject_duplicate_keys(const std::string& text, const std::string& source_name);

// One node of a loaded document, with the file name and the dotted path that led to it.
class ConfigNode {
 public:
  static ConfigNode load_file(const std::string& path);
  static ConfigNode load_string(const std::string& text, const std::string& source_name);

  const std::string& source() const { return *source_; }
  const std::string& path() const { return path_; }
  const YAML::Node& yaml() const { return node_; }
  bool is_map() const { return node_.IsMap(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_scalar() const { return node_.IsScalar(); }
  bool is_null() const { return !node_.IsDefined() || node_.IsNull(); }

  // `file:line:column` of this node (1-based, as editors count).
  std::string location() const;
  [[noreturn]] void fail(std::string_view message) const;

  // Rejects any key of this mapping that is not in `allowed`, naming the offender and the keys
  // that are allowed. Also rejects a node that is not a mapping.
  void expect_keys(std::initializer_list<std::string_view> allowed) const;
  void expect_keys(const std::vector<std::string>& allowed) const;

  bool has(std::string_view key) const;
  ConfigNode at(std::string_view key) const;                        // required
  std::optional<ConfigNode> find(std::string_view key) const;       // optional
  std::vector<ConfigNode> items() const;                            // sequence elements
  std::vector<std::pair<std::string, ConfigNode>> entries() const;  // mapping entries in order

  // Scalar conversions; a wrong type fails with the expected type in the message.
  std::string as_string() const;
  double as_double() const;
  long long as_int() const;
  bool as_bool() const;

  // Field access with defaults and closed-interval range checks.
  std::string get_string(std::string_view key) const { return at(key).as_string(); }
  std::string get_string(std::string_view key, std::string_view fallback) const;
  std::string get_choice(std::string_view key, std::initializer_list<std::string_view> choices,
                         std::string_view fallback) const;
  double get_double(std::string_view key, double lo = -std::numeric_limits<double>::infinity(),
                    double hi = std::numeric_limits<double>::infinity()) const;
  double get_double(std::string_view key, double fallback, double lo, double hi) const;
  long long get_int(std::string_view key, long long lo, long long hi) const;
  long long get_int(std::string_view key, long long fallback, long long lo, long long hi) const;
  bool get_bool(std::string_view key, bool fallback) const;

  // Range check of an already converted value, reported at this node.
  double check_range(double value, double lo, double hi) const;

 private:
  ConfigNode(YAML::Node node, std::shared_ptr<const std::string> source, std::string path);
  std::string child_path(std::string_view key) const;
  std::string key_text(const YAML::Node& key) const;

  YAML::Node node_;
  std::shared_ptr<const std::string> source_;
  std::string path_;
};

}  // namespace leakmon::config
