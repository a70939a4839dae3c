#include "registers/lookup.hpp"

#include <algorithm>
#include <string>
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
