#include "config/yaml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <system_error>

namespace leakmon::config {
namespace {

std::string mark_location(const std::string& source, const YAML::Mark& mark) {
  if (mark.is_null()) return source;
  return fmt::format("{}:{}:{}", source, mark.line + 1, mark.column + 1);
}

// Walks the parser's events (the node API has already merged duplicate keys away) and remembers
// the first key that repeats within one mapping. Each open collection is a frame; a mapping's
// children alternate key, value, so the even-numbered ones are keys.
class DuplicateKeyFinder final : public YAML::EventHandler {
 public:
  struct Duplicate {
    std::string key;
    YAML::Mark first;
    YAML::Mark second;
  };
  const std::optional<Duplicate>& duplicate() const { return duplicate_; }

  void OnDocumentStart(const YAML::Mark&) override { stack_.clear(); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { child(mark, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { child(mark, nullptr); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                const std::string& value) override {
    child(mark, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    child(mark, nullptr);
    stack_.push_back(Frame{false, 0, {}});
  }
  void OnSequenceEnd() override { pop(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    child(mark, nullptr);
    stack_.push_back(Frame{true, 0, {}});
  }
  void OnMapEnd() override { pop(); }

 private:
  struct Frame {
    bool is_map;
    std::size_t children;
    std::map<std::string, YAML::Mark> keys;
  };
  // A node begins; `scalar` is its text when it is a scalar (only scalar keys are compared).
  void child(const YAML::Mark& mark, const std::string* scalar) {
    if (stack_.empty()) return;
    Frame& parent = stack_.back();
    const bool is_key = parent.is_map && parent.children % 2 == 0;
    ++parent.children;
    if (!is_key || scalar == nullptr || duplicate_) return;
    const auto [it, inserted] = parent.keys.emplace(*scalar, mark);
    if (!inserted) duplicate_ = Duplicate{*scalar, it->second, mark};
  }
  void pop() {
    if (!stack_.empty()) stack_.pop_back();
  }

  std::vector<Frame> stack_;
  std::optional<Duplicate> duplicate_;
};

void append_escaped(std::string& out, unsigned code) {
  out += code < 0x100 ? fmt::format("\\x{:02x}", code) : fmt::format("\\u{:04x}", code);
}

}  // namespace

std::size_t utf8_sequence(std::string_view text, std::size_t i, unsigned& code) {
  const auto byte = static_cast<unsigned char>(text[i]);
  if (byte < 0x80) {
    code = byte;
    return 1;
  }
  const std::size_t length = byte >= 0xf0 ? 4 : byte >= 0xe0 ? 3 : byte >= 0xc0 ? 2 : 0;
  if (length == 0 || byte >= 0xf5 || i + length > text.size()) return 0;
  code = length == 4 ? byte & 0x07u : length == 3 ? byte & 0x0fu : byte & 0x1fu;
  for (std::size_t k = 1; k < length; ++k) {
    const auto next = static_cast<unsigned char>(text[i + k]);
    if ((next & 0xc0u) != 0x80u) return 0;
    code = (code << 6) | (next & 0x3fu);
  }
  static constexpr unsigned kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};
  if (code < kSmallest[length] || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff)) return 0;
  return length;
}

std::string printable(std::string_view text, std::size_t max_bytes) {
  std::string out;
  out.reserve(std::min(text.size(), max_bytes) + 8);
  std::size_t i = 0;
  while (i < text.size()) {
    if (out.size() >= max_bytes) {
      out += "...";
      break;
    }
    const auto byte = static_cast<unsigned char>(text[i]);
    if (byte < 0x80) {
      if (byte < 0x20 || byte == 0x7f) {
        append_escaped(out, byte);
      } else {
        out += static_cast<char>(byte);
      }
      ++i;
      continue;
    }
    unsigned code = 0;
    const std::size_t length = utf8_sequence(text, i, code);
    if (length == 0) {
      out += "\xef\xbf\xbd";  // U+FFFD
      ++i;
      continue;
    }
    if (code < 0xa0) {
      append_escaped(out, code);  // C1 controls (0x9b is a terminal's CSI)
    } else {
      out.append(text.substr(i, length));
    }
    i += length;
  }
  return out;
}

void reject_duplicate_keys(const std::string& text, const std::string& source_name) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  DuplicateKeyFinder finder;
  // The first document only, as YAML::Load reads it (and yaml-cpp 0.7 can report further
  // "documents" without end on some malformed input).
  parser.HandleNextDocument(finder);
  if (const auto& dup = finder.duplicate()) {
    throw ConfigError(
        fmt::format("{}: duplicate key '{}' (first given at line {}, column {}); "
                    "only one of them would take effect",
                    mark_location(source_name, dup->second), printable(dup->key),
                    dup->first.line + 1, dup->first.column + 1));
  }
}

// YAML::Load reads the first document and silently drops the rest: two configurations pasted
// into one file would run the first. A marker line ("---" or "..." at column 0, which YAML
// allows nowhere else) after content starts a second document. Found on the text, because
// walking yaml-cpp's further documents can loop on malformed input.
static void reject_further_documents(const std::string& text, const std::string& source_name) {
  bool content = false;
  bool ended = false;
  std::size_t line_number = 0;
  for (std::size_t from = 0; from <= text.size();) {
    const std::size_t end = std::min(text.find('\n', from), text.size());
    std::string_view line(text.data() + from, end - from);
    from = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const auto marker = [&](std::string_view m) {
      return line.substr(0, 3) == m && (line.size() == 3 || line[3] == ' ' || line[3] == '\t');
    };
    if (marker("---") || marker("...")) {
      if (content && marker("---")) {
        throw ConfigError(
            fmt::format("{}:{}:1: a second YAML document ('---'); a configuration is one document "
                        "(only the first would take effect)",
                        source_name, line_number));
      }
      if (marker("...")) ended = content;
      const std::string_view rest = line.substr(3);
      if (marker("---") && rest.find_first_not_of(" \t") != std::string_view::npos &&
          rest[rest.find_first_not_of(" \t")] != '#') {
        content = true;  // "--- value": the document's content starts on the marker line
      }
      continue;
    }
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string_view::npos || line[first] == '#') continue;
    if (line[0] == '%' && !content) continue;  // a directive before the document
    if (ended) {
      throw ConfigError(fmt::format(
          "{}:{}:{}: content after the end of the YAML document ('...'); a configuration is "
          "one document",
          source_name, line_number, first + 1));
    }
    content = true;
  }
}

namespace {

// The lines of `text`, without their line ends.
std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  for (std::size_t from = 0; from <= text.size();) {
    const std::size_t end = std::min(text.find('\n', from), text.size());
    std::string_view line = text.substr(from, end - from);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    from = end + 1;
  }
  return lines;
}

bool is_content(std::string_view line) {
  const std::size_t first = line.find_first_not_of(' ');
  return first != std::string_view::npos && line[first] != '#';
}

// Columns (1-based) where block content starts on `line`: after the indentation, and after each
// list dash ("  - name: x" starts content at columns 3 and 5).
std::vector<std::size_t> content_columns(std::string_view line) {
  std::vector<std::size_t> columns;
  std::size_t at = line.find_first_not_of(' ');
  while (at != std::string_view::npos) {
    columns.push_back(at + 1);
    if (line[at] != '-' || at + 1 >= line.size() || line[at + 1] != ' ') break;
    at = line.find_first_not_of(' ', at + 1);
  }
  return columns;
}

// What is probably wrong where yaml-cpp stopped: the parser's own words name the grammar rule,
// an operator needs the mistake (indentation, tabs, an unclosed bracket, an unquoted colon).
std::string syntax_hint(const std::string& text, const YAML::Exception& e) {
  const auto lines = split_lines(text);
  const bool located = !e.mark.is_null() && e.mark.line >= 0;
  const std::size_t line_index = located ? static_cast<std::size_t>(e.mark.line) : lines.size();
  for (std::size_t i = 0; i <= line_index && i < lines.size(); ++i) {
    const std::string_view line = lines[i];
    const std::size_t first = line.find_first_not_of(" \t");
    const std::string_view indent = line.substr(0, std::min(first, line.size()));
    if (indent.find('\t') != std::string_view::npos && first != std::string_view::npos) {
      return fmt::format("line {} is indented with a tab: YAML indents with spaces only", i + 1);
    }
  }
  if (!located || line_index >= lines.size()) return "";
  const std::string_view here = lines[line_index];
  // The columns the content above begins at, nearest line first: where this line could belong.
  std::vector<std::size_t> above;
  std::size_t previous_line = 0;
  for (std::size_t i = line_index; i-- > 0;) {
    if (!is_content(lines[i])) continue;
    if (previous_line == 0) previous_line = i + 1;
    for (std::size_t column : content_columns(lines[i])) {
      if (std::find(above.begin(), above.end(), column) == above.end()) above.push_back(column);
    }
  }
  std::sort(above.begin(), above.end());
  const std::size_t column = here.find_first_not_of(' ') + 1;
  const std::string& msg = e.msg;
  if (msg.find("flow") != std::string::npos) {
    const bool map = msg.find("map") != std::string::npos;
    return fmt::format(
        "an inline {} opened with '{}' is not closed with '{}' (or a ',' is missing "
        "between its entries)",
        map ? "mapping" : "list", map ? '{' : '[', map ? '}' : ']');
  }
  if (msg.find("end of map not found") != std::string::npos ||
      msg.find("end of sequence not found") != std::string::npos ||
      msg.find("illegal block entry") != std::string::npos ||
      msg.find("block sequence entries are not allowed") != std::string::npos) {
    if (std::find(above.begin(), above.end(), column) == above.end() && !above.empty()) {
      return fmt::format(
          "probably wrong indentation: line {} starts at column {}, but the blocks above start "
          "at columns {}; entries of one mapping or list start in the same column",
          line_index + 1, column, fmt::join(above, ", "));
    }
    return fmt::format(
        "probably wrong indentation at line {}, or a list item ('- ') where a "
        "key was expected (or the other way round)",
        line_index + 1);
  }
  if (msg.find("illegal map value") != std::string::npos) {
    const auto prior =
        previous_line == 0 ? std::vector<std::size_t>{} : content_columns(lines[previous_line - 1]);
    if (!prior.empty() && column > prior.back()) {
      return fmt::format(
          "probably wrong indentation: line {} starts at column {}, deeper than line {} (column "
          "{}), so it reads as the continuation of that line's value",
          line_index + 1, column, previous_line, prior.back());
    }
    return "a ':' followed by a space where no key can start: a value that contains ': ' must be "
           "quoted ('...' or \"...\")";
  }
  return "";
}

}  // namespace

ConfigNode::ConfigNode(YAML::Node node, std::shared_ptr<const std::string> source, std::string path)
    : node_(std::move(node)), source_(std::move(source)), path_(std::move(path)) {}

ConfigNode ConfigNode::load_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw ConfigError(fmt::format(
        "{}: is a directory, not a configuration file (name the YAML file in it)", path));
  }
  std::ifstream in(path);
  if (!in) throw ConfigError(fmt::format("{}: cannot open file", path));
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(fmt::format("{}: cannot read file", path));
  return load_string(text.str(), path);
}

ConfigNode ConfigNode::load_string(const std::string& text, const std::string& source_name) {
  auto source = std::make_shared<const std::string>(source_name);
  try {
    YAML::Node root = YAML::Load(text);
    reject_duplicate_keys(text, source_name);
    reject_further_documents(text, source_name);
    if (!root.IsDefined() || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    return ConfigNode(root, source, "");
  } catch (const YAML::Exception& e) {
    const std::string hint = syntax_hint(text, e);
    if (hint.empty()) {
      throw ConfigError(
          fmt::format("{}: {}", mark_location(source_name, e.mark), printable(e.msg)));
    }
    throw ConfigError(fmt::format("{}: {} (YAML parser: {})", mark_location(source_name, e.mark),
                                  hint, printable(e.msg)));
  }
}

std::string ConfigNode::location() const { return mark_location(*source_, node_.Mark()); }

void ConfigNode::fail(std::string_view message) const {
  // Messages quote configuration content: escaped here, once, for every caller.
  const std::string safe = printable(message, 2000);
  if (path_.empty()) throw ConfigError(fmt::format("{}: {}", location(), safe));
  throw ConfigError(fmt::format("{}: {}: {}", location(), printable(path_), safe));
}

std::string ConfigNode::key_text(const YAML::Node& key) const {
  // A list or mapping as a key (`? [a, b]`) is valid YAML but names nothing here.
  if (!key.IsScalar()) ConfigNode(key, source_, path_).fail("a key must be plain text");
  return key.Scalar();
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
    const std::string key = key_text(kv.first);
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
    const std::string key = key_text(kv.first);
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
