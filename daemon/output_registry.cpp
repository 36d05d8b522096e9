#include "daemon/output_registry.hpp"

#include <fmt/format.h>

#include <vector>

#include "daemon/event_log.hpp"
#ifdef LEAKMON_HAVE_MODBUS_OUTPUT
#include "io/modbus/modbus_output.hpp"
#endif

namespace leakmon::daemon {
namespace {

constexpr OutputType kOutputTypes[] = {
    {"jsonl", make_jsonl_output},
#ifdef LEAKMON_HAVE_MODBUS_OUTPUT
    {"modbus", io::make_modbus_output},
#endif
};

}  // namespace

std::span<const OutputType> output_types() { return kOutputTypes; }

std::unique_ptr<EventSink> make_output(const config::ConfigNode& node) {
  const auto type_node = node.at("type");
  const std::string type = type_node.as_string();
  for (const auto& entry : kOutputTypes) {
    if (entry.type == type) return entry.factory(node);
  }
  std::vector<std::string_view> known;
  for (const auto& entry : kOutputTypes) known.push_back(entry.type);
  type_node.fail(fmt::format("unknown output type '{}' (known: {})", type, fmt::join(known, ", ")));
}

}  // namespace leakmon::daemon
