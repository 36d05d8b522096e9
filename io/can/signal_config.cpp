#include "io/can/signal_config.hpp"

#include <charconv>
#include <cmath>
#include <set>
#include <string>

namespace leakmon::io::can {

std::uint32_t read_can_id(const config::ConfigNode& node) {
  const std::string text = node.as_string();
  const bool hex = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
  const char* first = text.data() + (hex ? 2 : 0);
  const char* last = text.data() + text.size();
  std::uint64_t id = 0;
  auto [ptr, ec] = std::from_chars(first, last, id, hex ? 16 : 10);
  if (text.empty() || ec != std::errc() || ptr != last || id > kExtendedIdMask) {
    node.fail("expected a CAN identifier (decimal or 0x-prefixed hex, at most 0x1FFFFFFF), got '" +
              text + "'");
  }
  return static_cast<std::uint32_t>(id);
}

std::vector<SignalDef> read_signals(const config::ConfigNode& driver) {
  const double default_max_age = driver.get_double("max_age", kDefaultMaxAgeSeconds, 1e-4, 3600.0);
  const config::ConfigNode list = driver.at("signals");
  if (!list.is_sequence() || list.items().empty()) {
    list.fail("expected a non-empty list of signals");
  }
  std::vector<SignalDef> signals;
  std::set<std::string> channels;
  for (const auto& item : list.items()) {
    item.expect_keys({"channel", "id", "extended", "start_bit", "length", "byte_order", "signed",
                      "factor", "offset", "unit", "max_age"});
    SignalDef def;
    def.channel = item.get_string("channel");
    if (def.channel.empty()) item.at("channel").fail("channel name must not be empty");
    if (!channels.insert(def.channel).second) {
      item.at("channel").fail("channel '" + def.channel + "' is defined twice");
    }
    def.unit = item.get_string("unit", "");
    SignalLayout& layout = def.layout;
    layout.extended = item.get_bool("extended", false);
    layout.id = read_can_id(item.at("id"));
    if (!layout.extended && layout.id > kStandardIdMask) {
      item.at("id").fail(
          "standard id must fit in 11 bits (max 0x7FF); set extended: true for a "
          "29-bit id");
    }
    layout.start_bit = static_cast<unsigned>(item.get_int("start_bit", 0, 0, 511));
    layout.length = static_cast<unsigned>(item.get_int("length", 1, 64));
    layout.byte_order = item.get_choice("byte_order", {"intel", "motorola"}, "intel") == "intel"
                            ? ByteOrder::intel
                            : ByteOrder::motorola;
    layout.is_signed = item.get_bool("signed", false);
    layout.factor = item.get_double("factor", 1.0, -1e300, 1e300);
    if (layout.factor == 0.0) item.at("factor").fail("factor must not be zero");
    layout.offset = item.get_double("offset", 0.0, -1e300, 1e300);
    if (auto problem = layout_problem(layout); !problem.empty()) {
      item.at("length").fail(problem);
    }
    const double max_age = item.get_double("max_age", default_max_age, 1e-4, 3600.0);
    def.max_age_ns = std::llround(max_age * 1e9);
    signals.push_back(std::move(def));
  }
  return signals;
}

}  // namespace leakmon::io::can
