#include "daemon/output_registry.hpp"

#include "pipeline/event_log.hpp"
#include "io/modbus/modbus_output.hpp"
#include "io/mqtt/mqtt_output.hpp"

namespace leakmon::daemon {
namespace {

constexpr OutputType kOutputTypes[] = {
    {"jsonl", pipeline::make_jsonl_output},
    {"modbus", io::make_modbus_output},
    {"mqtt", io::mqtt::make_mqtt_output},
};

}  // namespace

std::span<const OutputType> output_types() { return kOutputTypes; }

std::unique_ptr<io::EventSink> make_output(const config::ConfigNode& node) {
  return make_plugin(output_types(), "output", node);
}

}  // namespace leakmon::daemon
