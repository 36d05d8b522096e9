// The roles an actuator's signals play, by their MODEL.md and FORMATS.md names: chamber
// pressures p1 and p2, valve command u, position x and its reference xref, supply pressure ps,
// oil temperature temp. A role's name is its capture column and its key under an actuator's
// `channels:`, so the enum lives on the ground floor where every folder that reads captures,
// configurations or samples can include it. Every list of roles (the configuration's keys, the
// replay's default columns, where a role sits in a sample, the state fingerprint) is kRoles.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace leakmon::capture {

enum class Role : std::uint8_t { p1, p2, u, x, xref, ps, temp };

// Every role, in the order configurations, fingerprints and messages list them.
inline constexpr std::array<Role, 7> kRoles = {Role::p1,   Role::p2, Role::u,   Role::x,
                                               Role::xref, Role::ps, Role::temp};

inline constexpr std::string_view to_string(Role role) {
  constexpr std::array<std::string_view, kRoles.size()> kNames = {"p1",   "p2", "u",   "x",
                                                                  "xref", "ps", "temp"};
  return kNames[static_cast<std::size_t>(role)];
}

// The role named `name`, or nothing for a column that is no role (t, pt, a driver's own name).
inline constexpr std::optional<Role> parse_role(std::string_view name) {
  for (const Role role : kRoles) {
    if (to_string(role) == name) return role;
  }
  return std::nullopt;
}

// One value per role, indexed by Role.
template <typename T>
class ByRole {
 public:
  constexpr ByRole() = default;
  constexpr explicit ByRole(const T& every) { values_.fill(every); }

  constexpr T& operator[](Role role) { return values_[static_cast<std::size_t>(role)]; }
  constexpr const T& operator[](Role role) const { return values_[static_cast<std::size_t>(role)]; }
  friend bool operator==(const ByRole&, const ByRole&) = default;

 private:
  std::array<T, kRoles.size()> values_{};
};

}  // namespace leakmon::capture
