// Settings rows carry the member they fill (registers/fills.hpp): every member
// of the settings structs is filled by exactly one row, and settings survive
// the trip through the registers unchanged.
#include <catch2/catch.hpp>

#include <array>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "homing/settings.hpp"
#include "registers/codec.hpp"
#include "registers/defaults.hpp"
#include "registers/lookup.hpp"
#include "registers/table.hpp"

using namespace registers;
using homing::Settings;

namespace {

// Counts the members of an aggregate without naming them: the largest number
// of initializers it accepts from a value that converts to anything.
struct AnyMember {
  template <class T>
  operator T() const;  // NOLINT: only used unevaluated
};
template <class T, class... Given>
constexpr std::size_t member_count() {
  if constexpr (requires { T{Given{}..., AnyMember{}}; }) return member_count<T, Given..., AnyMember>();
  else return sizeof...(Given);
}
static_assert(member_count<homing::AxisSettings>() > 20, "the member count trick works on AxisSettings");

std::vector<const Register*> settings_rows() {
  std::vector<const Register*> out;
  for (const Register& r : registers_of(Unit::module))
    if (r.persisted) out.push_back(&r);
  return out;
}

// The bytes of Settings that a row's setter writes: those that hold the same
// value after the same write over two different backgrounds.
static_assert(std::is_trivially_copyable_v<Settings>);
std::vector<bool> bytes_written(const Register& reg, std::int64_t raw) {
  std::array<Settings, 2> s{};
  std::array<std::array<unsigned char, sizeof(Settings)>, 2> bytes{};
  for (std::size_t k = 0; k < 2; ++k) {
    std::memset(static_cast<void*>(&s[k]), k == 0 ? 0x00 : 0xFF, sizeof(Settings));
    set_setting_raw(s[k], reg, raw);
    std::memcpy(bytes[k].data(), static_cast<const void*>(&s[k]), sizeof(Settings));
  }
  std::vector<bool> out(sizeof(Settings));
  for (std::size_t i = 0; i < sizeof(Settings); ++i) out[i] = bytes[0][i] == bytes[1][i];
  return out;
}

// A raw value in the row's range; for flags and enums every value is drawn.
std::int64_t random_raw(const Register& reg, std::mt19937_64& rng) {
  return std::uniform_int_distribution<std::int64_t>(reg.min, reg.max)(rng);
}

}  // namespace

TEST_CASE("every settings row fills a member, and no two rows fill the same bytes") {
  const auto rows = settings_rows();
  REQUIRE(!rows.empty());
  std::vector<const Register*> owner(sizeof(Settings), nullptr);
  for (const Register* r : rows) {
    INFO(r->name());
    REQUIRE(r->setting.bound());
    const auto written = bytes_written(*r, r->max);
    std::size_t n = 0;
    for (std::size_t i = 0; i < written.size(); ++i) {
      if (!written[i]) continue;
      ++n;
      INFO("byte " << i << " is also filled by " << (owner[i] ? owner[i]->name() : std::string("-")));
      CHECK(owner[i] == nullptr);
      owner[i] = r;
    }
    CHECK(n > 0);
  }
}

TEST_CASE("every member of AxisSettings and GlobalSettings is filled by exactly one row per axis or slot") {
  // Rows filling the same member share its getter; an array member is filled
  // by one row per element.
  std::map<std::pair<const void*, int>, std::vector<const Register*>> by_member;
  for (const Register* r : settings_rows())
    by_member[{reinterpret_cast<const void*>(r->setting.get), r->axis}].push_back(r);

  std::size_t axis_members = 0, global_members = 0;
  for (const auto& [key, rows] : by_member) {
    const SettingAccess& f = rows.front()->setting;
    INFO(rows.front()->name());
    CHECK(rows.size() == (f.elements == 0 ? 1u : f.elements));
    for (std::size_t i = 0; i < rows.size(); ++i) CHECK(rows[i]->slot == (f.elements == 0 ? 0 : i));
    if (key.second == 0) ++axis_members;
    if (key.second < 0) ++global_members;
  }
  CHECK(axis_members == member_count<homing::AxisSettings>());
  CHECK(global_members == member_count<homing::GlobalSettings>());
  for (std::size_t a = 1; a < homing::kAxisCount; ++a) {
    std::size_t n = 0;
    for (const auto& [key, rows] : by_member) n += key.second == static_cast<int>(a);
    CHECK(n == axis_members);
  }
}

TEST_CASE("every raw value of every settings row survives registers to settings to registers") {
  std::mt19937_64 rng(14);
  for (int round = 0; round < 200; ++round) {
    Settings s = default_settings();
    std::map<std::string, std::int64_t> want;
    for (const Register* r : settings_rows()) {
      const std::int64_t raw = round == 0 ? r->min : round == 1 ? r->max : random_raw(*r, rng);
      set_setting_raw(s, *r, raw);
      want[r->name()] = raw;
    }
    for (const Register* r : settings_rows()) {
      INFO(r->name());
      CHECK(setting_raw(s, *r) == want.at(r->name()));
    }
    CHECK(settings_to_raw(s) == want);
  }
}

TEST_CASE("settings survive settings to registers to settings over every row") {
  std::mt19937_64 rng(15);
  for (int round = 0; round < 200; ++round) {
    Settings s = default_settings();
    for (const Register* r : settings_rows()) set_setting_raw(s, *r, random_raw(*r, rng));
    const auto back = settings_from_raw(settings_to_raw(s));
    CHECK(back.complete());
    CHECK(back.unknown.empty());
    CHECK(back.settings == s);
  }
}

TEST_CASE("every field a settings fault can name is a per-axis setting register") {
  for (const auto& f : homing::kAxisFieldInfo) {
    if (f.value == homing::AxisField::none) continue;
    for (const auto letter : homing::kAxisLetters) {
      const std::string name = "axis." + std::string(letter) + "." + std::string(f.name);
      INFO(name);
      const Register* r = find_register(name);
      REQUIRE(r != nullptr);
      CHECK(r->persisted);
    }
  }
}
