#include "io/modbus/request_plan.hpp"

#include <algorithm>
#include <numeric>
#include <tuple>

namespace leakmon::io::modbus {

std::vector<ReadRequest> plan_requests(std::span<const ChannelSpec> channels, int max_registers) {
  std::vector<std::size_t> order(channels.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto key = [&](std::size_t i) {
    const ChannelSpec& c = channels[i];
    return std::make_tuple(c.unit_id, static_cast<int>(c.register_type), c.address, c.width());
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return key(a) < key(b); });

  std::vector<ReadRequest> requests;
  for (std::size_t index : order) {
    const ChannelSpec& channel = channels[index];
    const int limit = is_bit_type(channel.register_type) ? kMaxBitsPerRequest : max_registers;
    const int end = channel.address + channel.width();
    if (!requests.empty()) {
      ReadRequest& last = requests.back();
      const bool same_table =
          last.unit_id == channel.unit_id && last.register_type == channel.register_type;
      const bool touches = channel.address <= last.address + last.count;
      const int merged_count = std::max(end, last.address + last.count) - last.address;
      if (same_table && touches && merged_count <= limit) {
        last.count = merged_count;
        last.slots.push_back({index, channel.address - last.address});
        continue;
      }
    }
    requests.push_back(
        {channel.unit_id, channel.register_type, channel.address, channel.width(), {{index, 0}}});
  }
  return requests;
}

}  // namespace leakmon::io::modbus
