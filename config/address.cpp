#include "config/address.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>

namespace leakmon::config {
namespace {

bool all_digits(std::string_view text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
  });
}

bool is_label(std::string_view label) {
  if (label.empty() || label.size() > 63 || label.front() == '-' || label.back() == '-') {
    return false;
  }
  return std::all_of(label.begin(), label.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-';
  });
}

}  // namespace

std::string host_problem(std::string_view host) {
  const std::string text(host);
  if (text.empty()) return "the host must not be empty";
  in_addr v4{};
  in6_addr v6{};
  if (::inet_pton(AF_INET, text.c_str(), &v4) == 1) return "";
  if (text.find(':') != std::string::npos) {
    if (::inet_pton(AF_INET6, text.c_str(), &v6) == 1) return "";
    return fmt::format("'{}' is not an IPv6 address", printable(text));
  }
  std::string_view name = host;
  if (name.back() == '.') name.remove_suffix(1);  // a fully qualified name's root
  if (name.find_first_not_of("0123456789.") == std::string_view::npos) {
    return fmt::format("'{}' is not an IPv4 address (four numbers 0..255 separated by dots)",
                       printable(text));
  }
  if (name.size() > 253) return fmt::format("'{}' is too long for a host name", printable(text));
  std::string_view last;
  for (std::size_t from = 0; from <= name.size();) {
    const std::size_t dot = std::min(name.find('.', from), name.size());
    last = name.substr(from, dot - from);
    if (!is_label(last)) {
      return fmt::format(
          "'{}' is neither an IP address nor a host name (names are letters, digits, '-' and "
          "dots)",
          printable(text));
    }
    from = dot + 1;
  }
  if (all_digits(last)) {
    return fmt::format("'{}' is not a host name: its last part is a number", printable(text));
  }
  return "";
}

std::string read_host(const ConfigNode& node) {
  const std::string host = node.as_string();
  if (const std::string problem = host_problem(host); !problem.empty()) node.fail(problem);
  return host;
}

}  // namespace leakmon::config
