#include "cli/args.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cstdio>

namespace leakmon::cli {

ArgParser::ArgParser(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

ArgParser& ArgParser::option(std::string name, std::string meta, std::string help,
                             std::optional<std::string> fallback, bool required) {
  specs_.push_back({std::move(name), std::move(meta), std::move(help), std::move(fallback),
                    required, false, false});
  return *this;
}

ArgParser& ArgParser::flag(std::string name, std::string help) {
  specs_.push_back({std::move(name), "", std::move(help), std::nullopt, false, true, false});
  return *this;
}

ArgParser& ArgParser::positional(std::string name, std::string help, bool required) {
  specs_.push_back({std::move(name), "", std::move(help), std::nullopt, required, false, true});
  return *this;
}

const ArgParser::Spec* ArgParser::lookup(std::string_view name) const {
  for (const auto& s : specs_) {
    if (!s.is_positional && s.name == name) return &s;
  }
  return nullptr;
}

bool ArgParser::parse(int argc, char** argv, int first) {
  std::size_t next_positional = 0;
  for (int i = first; i < argc; ++i) {
    std::string_view arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      std::fputs(help().c_str(), stdout);
      return false;
    }
    if (arg.starts_with("--")) {
      std::string_view body = arg.substr(2);
      std::optional<std::string> inline_value;
      if (auto eq = body.find('='); eq != std::string_view::npos) {
        inline_value = std::string(body.substr(eq + 1));
        body = body.substr(0, eq);
      }
      const Spec* spec = lookup(body);
      if (!spec) throw UsageError(fmt::format("unknown option '--{}'", body));
      if (spec->is_flag) {
        if (inline_value) throw UsageError(fmt::format("option '--{}' takes no value", body));
        values_[spec->name] = std::string("1");  // not = "1": GCC 12 -O3's -Wrestrict
        continue;
      }
      if (inline_value) {
        values_[spec->name] = *inline_value;
      } else {
        if (i + 1 >= argc)
          throw UsageError(fmt::format("option '--{}' needs a value ({})", body, spec->meta));
        values_[spec->name] = argv[++i];
      }
      continue;
    }
    std::size_t seen = 0;
    bool placed = false;
    for (const auto& s : specs_) {
      if (!s.is_positional) continue;
      if (seen++ == next_positional) {
        values_[s.name] = std::string(arg);
        ++next_positional;
        placed = true;
        break;
      }
    }
    if (!placed) throw UsageError(fmt::format("unexpected argument '{}'", arg));
  }
  for (const auto& s : specs_) {
    if (values_.contains(s.name)) continue;
    if (s.fallback) {
      values_[s.name] = *s.fallback;
    } else if (s.required) {
      throw UsageError(s.is_positional ? fmt::format("missing argument {}", s.name)
                                       : fmt::format("missing required option '--{}'", s.name));
    }
  }
  return true;
}

bool ArgParser::has(std::string_view name) const { return values_.find(name) != values_.end(); }

bool ArgParser::flag_set(std::string_view name) const { return has(name); }

std::optional<std::string> ArgParser::find(std::string_view name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string ArgParser::get(std::string_view name) const {
  auto it = values_.find(name);
  if (it == values_.end()) throw UsageError(fmt::format("missing option '--{}'", name));
  return it->second;
}

double ArgParser::get_double(std::string_view name) const {
  std::string s = get(name);
  double v = 0;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size()) {
    throw UsageError(fmt::format("option '--{}': '{}' is not a number", name, s));
  }
  return v;
}

long long ArgParser::get_int(std::string_view name) const {
  std::string s = get(name);
  long long v = 0;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size()) {
    throw UsageError(fmt::format("option '--{}': '{}' is not an integer", name, s));
  }
  return v;
}

std::string ArgParser::usage() const {
  std::string out = fmt::format("usage: leakmon {}", command_);
  for (const auto& s : specs_) {
    std::string item = s.is_positional ? s.name
                       : s.is_flag     ? fmt::format("--{}", s.name)
                                       : fmt::format("--{} {}", s.name, s.meta);
    out += (s.required && !s.fallback) ? fmt::format(" {}", item) : fmt::format(" [{}]", item);
  }
  return out + "\n";
}

std::string ArgParser::help() const {
  std::string out = usage() + "\n" + summary_ + "\n\n";
  for (const auto& s : specs_) {
    std::string item = s.is_positional ? s.name
                       : s.is_flag     ? fmt::format("--{}", s.name)
                                       : fmt::format("--{} {}", s.name, s.meta);
    out += fmt::format("  {:<26} {}", item, s.help);
    if (s.fallback && !s.fallback->empty()) out += fmt::format(" (default: {})", *s.fallback);
    out += "\n";
  }
  return out;
}

}  // namespace leakmon::cli
