#include "registers/defaults.hpp"

#include <fmt/format.h>

#include "registers/lookup.hpp"

namespace registers {
namespace {

template <class F>
void for_each_persisted(F&& f) {
  for (const Register& r : registers_of(Unit::module))
    if (r.persisted) f(r);
}

}  // namespace

homing::Settings default_settings() {
  homing::Settings s;
  for_each_persisted([&](const Register& r) { set_setting_raw(s, r, r.default_raw); });
  return s;
}

HostRegisters default_host_registers() {
  HostRegisters h;
  for (const Register& r : registers_of(Unit::module)) {
    const bool host_holding = r.table == Table::holding_register && !r.persisted;
    const bool host_coil = r.table == Table::coil && r.access == Access::rw;
    if (host_holding || host_coil) set_host_raw(h, r, r.default_raw);
  }
  return h;
}

std::vector<std::pair<std::string, std::int64_t>> persisted_defaults() {
  std::vector<std::pair<std::string, std::int64_t>> out;
  for_each_persisted([&](const Register& r) { out.emplace_back(r.name(), r.default_raw); });
  return out;
}

std::map<std::string, std::int64_t> settings_to_raw(const homing::Settings& settings) {
  std::map<std::string, std::int64_t> out;
  for_each_persisted([&](const Register& r) { out.emplace(r.name(), setting_raw(settings, r)); });
  return out;
}

SettingsFromRaw settings_from_raw(const std::map<std::string, std::int64_t>& stored) {
  SettingsFromRaw out{default_settings(), {}, {}, {}};
  for_each_persisted([&](const Register& r) {
    const auto it = stored.find(r.name());
    if (it == stored.end()) {
      out.defaulted.push_back(r.name());
      return;
    }
    if (it->second < r.min || it->second > r.max) {
      out.rejected.push_back(fmt::format("{} = {} is outside {}..{}; default {} used", r.name(), it->second,
                                         r.min, r.max, r.default_raw));
      return;
    }
    set_setting_raw(out.settings, r, it->second);
  });
  for (const auto& [name, raw] : stored) {
    const Register* r = find_register(name);
    if (!r || !r->persisted) out.unknown.push_back(name);
  }
  return out;
}

}  // namespace registers
