#include <gtest/gtest.h>

#include <vector>

#include "io/modbus/request_plan.hpp"

namespace leakmon::io::modbus {
namespace {

ChannelSpec channel(int address, DataType type, RegisterType reg = RegisterType::holding,
                    int unit = 1) {
  ChannelSpec c;
  // Not "c" + std::to_string(address), nor assigning "c": GCC 12 at -O3 reports a false
  // -Wrestrict for either.
  c.name = std::to_string(address);
  c.name.insert(c.name.begin(), 'c');
  c.address = address;
  c.data_type = type;
  c.register_type = reg;
  c.unit_id = unit;
  return c;
}

TEST(RequestPlan, ContiguousChannelsShareOneRequestInAnyConfiguredOrder) {
  const std::vector<ChannelSpec> channels = {
      channel(2, DataType::float32), channel(0, DataType::uint32), channel(4, DataType::int16)};
  const auto plan = plan_requests(channels, 125);
  ASSERT_EQ(plan.size(), 1U);
  EXPECT_EQ(plan[0].address, 0);
  EXPECT_EQ(plan[0].count, 5);
  ASSERT_EQ(plan[0].slots.size(), 3U);
  EXPECT_EQ(plan[0].slots[0].channel, 1U);
  EXPECT_EQ(plan[0].slots[0].offset, 0);
  EXPECT_EQ(plan[0].slots[1].channel, 0U);
  EXPECT_EQ(plan[0].slots[1].offset, 2);
  EXPECT_EQ(plan[0].slots[2].offset, 4);
}

TEST(RequestPlan, GapsSplitRequests) {
  const std::vector<ChannelSpec> channels = {channel(0, DataType::uint16),
                                             channel(2, DataType::uint16)};
  const auto plan = plan_requests(channels, 125);
  ASSERT_EQ(plan.size(), 2U);
  EXPECT_EQ(plan[0].count, 1);
  EXPECT_EQ(plan[1].address, 2);
}

TEST(RequestPlan, OverlappingChannelsReadTheSameRegisters) {
  const std::vector<ChannelSpec> channels = {
      channel(10, DataType::float32), channel(10, DataType::uint16), channel(11, DataType::uint16)};
  const auto plan = plan_requests(channels, 125);
  ASSERT_EQ(plan.size(), 1U);
  EXPECT_EQ(plan[0].address, 10);
  EXPECT_EQ(plan[0].count, 2);
}

TEST(RequestPlan, SplitsAtTheRegisterLimitWithoutCuttingAChannel) {
  std::vector<ChannelSpec> channels;
  for (int i = 0; i < 100; ++i) channels.push_back(channel(2 * i, DataType::float32));
  const auto plan = plan_requests(channels, 125);
  ASSERT_EQ(plan.size(), 2U);
  EXPECT_EQ(plan[0].count, 124);  // 62 FLOAT32s; the 63rd would need registers 124..125
  EXPECT_EQ(plan[1].address, 124);
  EXPECT_EQ(plan[1].count, 76);
  for (const auto& request : plan) EXPECT_LE(request.count, 125);
  EXPECT_EQ(plan[0].slots.size() + plan[1].slots.size(), 100U);
}

TEST(RequestPlan, SmallerConfiguredLimitIsHonoured) {
  std::vector<ChannelSpec> channels;
  for (int i = 0; i < 10; ++i) channels.push_back(channel(i, DataType::uint16));
  const auto plan = plan_requests(channels, 4);
  ASSERT_EQ(plan.size(), 3U);
  EXPECT_EQ(plan[2].count, 2);
}

TEST(RequestPlan, UnitsAndRegisterTypesAreSeparateTables) {
  const std::vector<ChannelSpec> channels = {channel(0, DataType::uint16, RegisterType::holding, 1),
                                             channel(1, DataType::uint16, RegisterType::holding, 2),
                                             channel(1, DataType::uint16, RegisterType::input, 1),
                                             channel(0, DataType::uint16, RegisterType::coil, 1),
                                             channel(1, DataType::uint16, RegisterType::coil, 1)};
  const auto plan = plan_requests(channels, 125);
  ASSERT_EQ(plan.size(), 4U);
  int coil_requests = 0;
  for (const auto& request : plan)
    if (request.register_type == RegisterType::coil) {
      ++coil_requests;
      EXPECT_EQ(request.count, 2);
    }
  EXPECT_EQ(coil_requests, 1);
}

TEST(RequestPlan, BitsSplitAt2000) {
  std::vector<ChannelSpec> channels;
  for (int i = 0; i < 2500; ++i)
    channels.push_back(channel(i, DataType::uint16, RegisterType::coil));
  const auto plan = plan_requests(channels, 125);
  ASSERT_EQ(plan.size(), 2U);
  EXPECT_EQ(plan[0].count, 2000);
  EXPECT_EQ(plan[1].count, 500);
}

}  // namespace
}  // namespace leakmon::io::modbus
