#pragma once
// The names and texts of the engine's enums, declared once, beside each enum,
// in a table whose entry i is the value i (the values are register values,
// dense from 0). The engine's logs, the register table, hmi_maps/ and the
// tools all read these tables; nothing else spells a value's name.
//
// Each enum header declares its table and an `enum_table(E)` overload that
// returns it, so `name_of(value)` and `text_of(value)` work for every enum.
#include <cstddef>
#include <span>
#include <string_view>

namespace homing {

template <class E>
struct EnumInfo {
  E value;
  std::string_view name;  // stable identifier: logs, exports, homingctl, register value names
  std::string_view text;  // what it means, for people (HMI texts, register descriptions)
};

// Entry i holds value i, and the last entry is `last`: the table lists every
// value of the enum, in order (checked by a static_assert beside each table).
template <class Entry, std::size_t N, class E>
constexpr bool lists_every_value(const Entry (&table)[N], E last) {
  for (std::size_t i = 0; i < N; ++i)
    if (static_cast<std::size_t>(table[i].value) != i) return false;
  return static_cast<std::size_t>(last) + 1 == N;
}

// The entry of a value, or nullptr for a number outside the enum (a value
// read from a register or a file may be anything).
template <class E>
constexpr auto entry_of(E value) -> decltype(&enum_table(value)[0]) {
  const auto table = enum_table(value);
  const auto i = static_cast<std::size_t>(value);
  return i < table.size() ? &table[i] : nullptr;
}

template <class E>
constexpr std::string_view name_of(E value) {
  const auto* e = entry_of(value);
  return e ? e->name : "?";
}

template <class E>
constexpr std::string_view text_of(E value) {
  const auto* e = entry_of(value);
  return e ? e->text : "?";
}

}  // namespace homing
