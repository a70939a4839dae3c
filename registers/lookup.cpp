#include "registers/lookup.hpp"

#include <algorithm>
#include <string>
#include <tuple>
#include <unordered_map>

namespace registers {

const Register* find_register(Unit unit, Table table, std::uint16_t address) {
  // all_registers() is sorted by (unit, table, address): binary search for the
  // last register starting at or before `address`, then see if it covers it.
  const auto regs = all_registers();
  auto it = std::upper_bound(regs.begin(), regs.end(), std::make_tuple(unit, table, address),
                             [](const auto& key, const Register& r) {
                               return key < std::make_tuple(r.unit, r.table, r.address);
                             });
  if (it == regs.begin()) return nullptr;
  const Register& r = *std::prev(it);
  if (r.unit != unit || r.table != table || r.end() <= address) return nullptr;
  return &r;
}

std::span<const Register> registers_overlapping(Unit unit, Table table, std::uint16_t first, std::size_t count) {
  // Registers of one (unit, table) do not overlap, so their ends rise with
  // their addresses as the table's order does.
  const auto regs = all_registers();
  const auto before = [&](const Register& r) { return std::tie(r.unit, r.table) < std::tie(unit, table); };
  const auto same = [&](const Register& r) { return r.unit == unit && r.table == table; };
  const auto begin = std::partition_point(regs.begin(), regs.end(), [&](const Register& r) {
    return before(r) || (same(r) && r.end() <= first);
  });
  const auto end = std::partition_point(begin, regs.end(), [&](const Register& r) {
    return same(r) && std::size_t{r.address} < std::size_t{first} + count;
  });
  return {begin, end};
}

const Register* find_register(std::string_view name) {
  // Built once, on first use; names are unique (checked by the tests).
  static const auto index = [] {
    std::unordered_map<std::string, const Register*> m;
    for (const Register& r : all_registers()) m.emplace(r.name(), &r);
    return m;
  }();
  const auto it = index.find(std::string(name));
  return it == index.end() ? nullptr : it->second;
}

}  // namespace registers
