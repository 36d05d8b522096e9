// Fuzzes the Modbus register decoders and the request planner with arbitrary register words,
// data types, byte orders and channel maps. Invariants beyond "no crash, no UB": integer types
// decode to integers in range, encoding a decoded value gives the same words back, the four
// byte orders are the documented permutations of one another, and every planned request stays
// within the protocol limit and covers each of its channels exactly once.
// fuzz-sources: io/modbus/register_decoding.cpp io/modbus/request_plan.cpp
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "fuzz/fuzz_input.hpp"
#include "io/modbus/register_decoding.hpp"
#include "io/modbus/request_plan.hpp"

using namespace leakmon::io::modbus;
using leakmon::fuzz::FuzzInput;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

std::uint16_t swapped(std::uint16_t w) { return static_cast<std::uint16_t>(w << 8 | w >> 8); }

void check_decoding(FuzzInput& in) {
  const auto type = static_cast<DataType>(in.byte() % 6);
  const auto order = static_cast<ByteOrder>(in.byte() % 4);
  const std::size_t given = in.byte() % 6;  // sometimes fewer words than the type needs
  std::vector<std::uint16_t> words(given);
  for (auto& w : words) w = in.u16_big_endian();
  const std::size_t n = register_count(type);
  const double value = decode_registers(words, type, order);
  if (given < n) {
    require(std::isnan(value));
    return;
  }
  if (type != DataType::float32 && type != DataType::float64) {
    require(std::trunc(value) == value);
    std::array<std::uint16_t, 4> again{};
    encode_registers(value, type, order, again);
    require(
        std::equal(again.begin(), again.begin() + static_cast<std::ptrdiff_t>(n), words.begin()));
  } else if (!std::isnan(value)) {
    std::array<std::uint16_t, 4> again{};
    encode_registers(value, type, order, again);
    require(
        std::equal(again.begin(), again.begin() + static_cast<std::ptrdiff_t>(n), words.begin()));
  }
  // ABCD of the words == CDAB of the words reversed == BADC of the bytes swapped.
  std::vector<std::uint16_t> reversed(words.begin(),
                                      words.begin() + static_cast<std::ptrdiff_t>(n));
  std::reverse(reversed.begin(), reversed.end());
  std::vector<std::uint16_t> swapped_words(n);
  std::transform(words.begin(), words.begin() + static_cast<std::ptrdiff_t>(n),
                 swapped_words.begin(), swapped);
  const double abcd = decode_registers(words, type, ByteOrder::abcd);
  const auto same = [&](double other) {
    require((std::isnan(abcd) && std::isnan(other)) || abcd == other);
  };
  if (type != DataType::int16 && type != DataType::uint16)
    same(decode_registers(reversed, type, ByteOrder::cdab));
  same(decode_registers(swapped_words, type, ByteOrder::badc));
}

void check_plan(FuzzInput& in) {
  const std::size_t count = in.byte() % 40;
  const int limit = 4 + in.byte() % 122;
  std::vector<ChannelSpec> channels(count);
  for (auto& c : channels) {
    c.unit_id = in.byte() % 3;
    c.register_type = static_cast<RegisterType>(in.byte() % 4);
    c.data_type = static_cast<DataType>(in.byte() % 6);
    c.address = in.u16_big_endian() % 300;  // dense enough to merge often
  }
  const auto plan = plan_requests(channels, limit);
  std::vector<int> seen(count, 0);
  for (const ReadRequest& request : plan) {
    const int max = is_bit_type(request.register_type) ? kMaxBitsPerRequest : limit;
    require(request.count >= 1 && request.count <= max);
    require(!request.slots.empty());
    for (const ChannelSlot& slot : request.slots) {
      require(slot.channel < count);
      const ChannelSpec& c = channels[slot.channel];
      ++seen[slot.channel];
      require(c.unit_id == request.unit_id && c.register_type == request.register_type);
      require(slot.offset == c.address - request.address);
      require(slot.offset >= 0 && slot.offset + c.width() <= request.count);
    }
  }
  for (int s : seen) require(s == 1);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  if (in.byte() % 2 == 0) {
    check_decoding(in);
  } else {
    check_plan(in);
  }
  return 0;
}
