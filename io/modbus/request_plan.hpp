// Which requests one poll sends: channels' register ranges merged per unit and register type,
// so that contiguous values arrive in one request (one round trip, one consistent snapshot),
// split where the ranges leave a gap (reading unmapped registers may draw exception replies)
// and where a request would exceed the protocol limit (125 registers, 2000 bits).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "io/modbus/modbus_config.hpp"

namespace leakmon::io::modbus {

inline constexpr int kMaxBitsPerRequest = 2000;

struct ChannelSlot {
  std::size_t channel = 0;  // index into the configured channels
  int offset = 0;           // first register (or bit) of the channel within the request
};

struct ReadRequest {
  int unit_id = 1;
  RegisterType register_type = RegisterType::holding;
  int address = 0;
  int count = 0;
  std::vector<ChannelSlot> slots;
};

// `max_registers` must be at least 4, the widest channel (FLOAT64); the configuration enforces it.
std::vector<ReadRequest> plan_requests(std::span<const ChannelSpec> channels, int max_registers);

}  // namespace leakmon::io::modbus
