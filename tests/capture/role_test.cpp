// The roles of an actuator's signals: one enum, one name table (capture/role.hpp). The names are
// capture columns, configuration keys and part of every saved state's fingerprint, so they and
// their order are a format: a change here fails this test before it orphans the state files.
#include "capture/role.hpp"

#include <gtest/gtest.h>

#include <string>

namespace leakmon::capture {
namespace {

TEST(Role, NamesAreTheCaptureColumnsInTheirOrder) {
  std::string names;
  for (const Role role : kRoles) names += std::string(to_string(role)) + " ";
  EXPECT_EQ(names, "p1 p2 u x xref ps temp ");
}

TEST(Role, EveryNameReadsBackAndNothingElseIsARole) {
  for (const Role role : kRoles) {
    const auto parsed = parse_role(to_string(role));
    ASSERT_TRUE(parsed.has_value()) << to_string(role);
    EXPECT_EQ(*parsed, role);
  }
  for (const char* other : {"t", "pt", "P1", "p1 ", "", "x2", "temperature"}) {
    EXPECT_FALSE(parse_role(other).has_value()) << other;
  }
  static_assert(parse_role("xref") == Role::xref, "usable at compile time");
}

TEST(Role, ByRoleHoldsOneValuePerRole) {
  ByRole<int> index(-1);
  for (const Role role : kRoles) EXPECT_EQ(index[role], -1);
  index[Role::x] = 3;
  index[Role::p1] = 0;
  EXPECT_EQ(index[Role::x], 3);
  EXPECT_EQ(index[Role::p1], 0);
  EXPECT_EQ(index[Role::p2], -1);
  ByRole<int> same(-1);
  same[Role::p1] = 0;
  EXPECT_FALSE(index == same);
  same[Role::x] = 3;
  EXPECT_TRUE(index == same);
}

}  // namespace
}  // namespace leakmon::capture
