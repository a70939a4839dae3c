#pragma once
// fills<&Member>: the SettingAccess of a settings row, made from a pointer to
// the member of homing::AxisSettings or homing::GlobalSettings it fills. The
// member's type decides the conversion: double = engineering value (raw ×
// the row's scale, in the codec), bool = flag 0/1, enum = its register value,
// integer = the raw value; std::array members are filled element by element
// (the row's slot). Used by registers/table.cpp only.
#include <array>
#include <concepts>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "homing/settings.hpp"
#include "registers/codec.hpp"
#include "registers/table.hpp"

namespace registers {
namespace fills_detail {

template <class M>
struct member_of;
template <class C, class T>
struct member_of<T C::*> {
  using owner = C;
  using type = T;
};

template <class T>
struct element_of {
  using type = T;
  static constexpr std::size_t count = 0;
};
template <class T, std::size_t N>
struct element_of<std::array<T, N>> {
  using type = T;
  static constexpr std::size_t count = N;
};

template <auto Member>
using Owner = typename member_of<decltype(Member)>::owner;
template <auto Member>
using Element = element_of<typename member_of<decltype(Member)>::type>;

template <auto Member>
inline constexpr bool kPerAxis = std::is_same_v<Owner<Member>, homing::AxisSettings>;

// The member (or array element) of `settings` that `reg` names.
template <auto Member, class S>
auto& member_in(S& settings, const Register& reg) {
  auto& owner = [&]() -> auto& {
    if constexpr (kPerAxis<Member>) return settings.axes[static_cast<std::size_t>(reg.axis)];
    else return settings.global;
  }();
  if constexpr (Element<Member>::count > 0) return (owner.*Member)[reg.slot];
  else return owner.*Member;
}

template <class T>
std::int64_t raw_of(const Register& reg, const T& value) {
  if constexpr (std::is_same_v<T, double>) return to_raw(reg, value);
  else if constexpr (std::is_same_v<T, bool>) return value ? 1 : 0;
  else if constexpr (std::is_enum_v<T>) return static_cast<std::int64_t>(std::to_underlying(value));
  else return static_cast<std::int64_t>(value);
}

template <class T>
T value_of(const Register& reg, std::int64_t raw) {
  if constexpr (std::is_same_v<T, double>) return to_engineering(reg, raw);
  else if constexpr (std::is_same_v<T, bool>) return raw != 0;
  else return static_cast<T>(raw);
}

// An engine enum's largest value comes from its table (enum_info.hpp).
template <class T>
constexpr std::int64_t max_raw() {
  if constexpr (std::is_enum_v<T>) {
    if constexpr (requires { enum_table(T{}); })
      return static_cast<std::int64_t>(enum_table(T{}).size()) - 1;
    else return std::numeric_limits<std::underlying_type_t<T>>::max();
  } else if constexpr (std::is_integral_v<T>) {
    return static_cast<std::int64_t>(std::numeric_limits<T>::max());
  } else {
    return 0;
  }
}

template <class T>
constexpr SettingAccess::Kind kind() {
  if constexpr (std::is_same_v<T, double>) return SettingAccess::Kind::real;
  else if constexpr (std::is_same_v<T, bool>) return SettingAccess::Kind::flag;
  else if constexpr (std::is_enum_v<T>) return SettingAccess::Kind::enumeration;
  else return SettingAccess::Kind::integer;
}

template <auto Member>
constexpr SettingAccess make() {
  using T = typename Element<Member>::type;
  static_assert(kPerAxis<Member> || std::is_same_v<Owner<Member>, homing::GlobalSettings>,
                "a settings row fills a member of homing::AxisSettings or homing::GlobalSettings");
  static_assert(std::is_same_v<T, double> || std::is_same_v<T, bool> || std::is_enum_v<T> ||
                    (std::is_integral_v<T> && std::is_unsigned_v<T>),
                "a setting is a double (engineering value), a bool, an enum or an unsigned integer");
  return SettingAccess{
      .kind = kind<T>(),
      .per_axis = kPerAxis<Member>,
      .elements = static_cast<std::uint8_t>(Element<Member>::count),
      .max_raw = max_raw<T>(),
      .get = [](const homing::Settings& s, const Register& reg) { return raw_of(reg, member_in<Member>(s, reg)); },
      .set = [](homing::Settings& s, const Register& reg,
                std::int64_t raw) { member_in<Member>(s, reg) = value_of<T>(reg, raw); },
  };
}

}  // namespace fills_detail

template <auto Member>
inline constexpr SettingAccess fills = fills_detail::make<Member>();

}  // namespace registers
