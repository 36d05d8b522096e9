// Network addresses written in a configuration: checked where they are read, so that a typo
// such as `host: 127.0.0.300` is an error at its file:line:column rather than a connection
// that fails at run time.
#pragma once

#include <string>
#include <string_view>

#include "config/yaml_reader.hpp"

namespace leakmon::config {

// Why `host` is not a usable host: an IPv4 address in dotted digits (all four parts 0..255), an
// IPv6 address, or a DNS name (labels of letters, digits and '-', 1..63 characters, at most 253
// in all, not all digits at the end: "10.0.0" is a cut-off address, not a name). Empty when it
// is one of these.
std::string host_problem(std::string_view host);

// The node's text as a host, failing at the node with host_problem() when it is not one.
std::string read_host(const ConfigNode& node);

}  // namespace leakmon::config
