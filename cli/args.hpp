// A small command-line parser for leakmon's subcommands: `--name value`, `--name=value`,
// boolean `--flag`s and positional arguments, with generated --help text. Errors are
// UsageError, which main() prints with the subcommand's usage line and exit code 2.
#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace leakmon::cli {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ArgParser {
 public:
  ArgParser(std::string command, std::string summary);

  // An option taking a value; `fallback` empty means required unless `optional_value`.
  ArgParser& option(std::string name, std::string meta, std::string help,
                    std::optional<std::string> fallback = std::nullopt, bool required = false);
  ArgParser& flag(std::string name, std::string help);
  ArgParser& positional(std::string name, std::string help, bool required = true);

  // Parses argv[first..argc). Returns false when --help was given (help already printed).
  bool parse(int argc, char** argv, int first = 1);

  bool has(std::string_view name) const;
  bool flag_set(std::string_view name) const;
  std::string get(std::string_view name) const;  // throws UsageError when absent
  std::optional<std::string> find(std::string_view name) const;
  double get_double(std::string_view name) const;
  long long get_int(std::string_view name) const;

  std::string usage() const;
  std::string help() const;

 private:
  struct Spec {
    std::string name, meta, help;
    std::optional<std::string> fallback;
    bool required = false;
    bool is_flag = false;
    bool is_positional = false;
  };
  const Spec* lookup(std::string_view name) const;

  std::string command_, summary_;
  std::vector<Spec> specs_;
  std::map<std::string, std::string, std::less<>> values_;
};

}  // namespace leakmon::cli
