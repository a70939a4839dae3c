// The write path's decision (server/write_plan.hpp): every refusal in its
// fixed order, each shown against the one after it in the same request, what
// an accepted plan carries, and that deciding changes nothing (the unlock
// guard counts a wrong code only when the service records the refusal).
#include <catch2/catch.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "homing/status.hpp"
#include "registers/defaults.hpp"
#include "registers/errors.hpp"
#include "registers/lookup.hpp"
#include "server/unlock_guard.hpp"
#include "server/edit_sessions.hpp"
#include "server/write_plan.hpp"

using namespace std::chrono_literals;
using registers::RefusalReason;
using registers::Table;

namespace {

constexpr std::uint32_t kCode = 4321;
constexpr std::uint16_t kHomeAxes = 40;     // cmd.home_axes
constexpr std::uint16_t kTrendCycles = 41;  // global.trend_cycles (default 20)
constexpr std::uint16_t kUnlock = 30;       // security.unlock

// One request's world: defaults, an idle machine, settings unlocked.
struct World {
  homing::Settings settings = registers::default_settings();
  registers::HostRegisters host = registers::default_host_registers();
  homing::Status status{};
  server::UnlockGuard guard{kCode, server::UnlockPolicy{}};
  server::UnlockGuard::Clock::time_point now{};
  bool client_may_write = true;
  bool locked = false;
  server::MachineCheck machine_check;
  server::ClientInfo client{1, server::Transport::tcp, "127.0.0.1:50000"};
  server::EditState edit_state = server::EditState::none;
  std::vector<registers::RawWrite> edit_staged;
  bool edit_full = false;

  std::expected<server::WritePlan, server::PlannedRefusal> plan(Table table, std::uint16_t start,
                                                                std::vector<std::uint16_t> values) const {
    const server::WriteState state{.settings = settings,
                                   .host = host,
                                   .status = status,
                                   .client_may_write = client_may_write,
                                   .locked = locked,
                                   .unlock_guard = guard,
                                   .now = now,
                                   .machine_check = &machine_check,
                                   .edit_state = edit_state,
                                   .edit_staged = edit_staged,
                                   .edit_sessions_full = edit_full};
    return server::plan_write(table, start, values, client, state);
  }
  void homing_runs() {
    status.homing = true;
    status.interlocks |= homing::interlock::homing_active;
  }
  void wiring_refuses() {
    machine_check = [](const homing::Settings&) { return std::optional<std::string>("no GPIO line for it"); };
  }
};

RefusalReason reason_of(const std::expected<server::WritePlan, server::PlannedRefusal>& p) {
  REQUIRE_FALSE(p.has_value());
  return p.error().refusal.reason;
}

std::uint16_t address_of(const std::expected<server::WritePlan, server::PlannedRefusal>& p) {
  REQUIRE_FALSE(p.has_value());
  return p.error().refusal.address;
}

}  // namespace

TEST_CASE("plan_write: a client outside --write-allow is refused before its certificate role is looked at") {
  World w;
  w.client_may_write = false;
  w.client.access = server::Access::read_only;
  const auto p = w.plan(Table::holding_register, kTrendCycles, {5});
  CHECK(reason_of(p) == RefusalReason::client_read_only);
  CHECK(p.error().refusal.code == registers::ExceptionCode::illegal_function);
}

TEST_CASE("plan_write: a role that may not write is refused before the value is range-checked") {
  World w;
  w.client.access = server::Access::read_only;
  CHECK(reason_of(w.plan(Table::holding_register, kTrendCycles, {60000})) == RefusalReason::role);
  w.client.access = server::Access::commands;  // commands, not settings
  CHECK(reason_of(w.plan(Table::holding_register, kTrendCycles, {5})) == RefusalReason::role);
}

TEST_CASE("plan_write: a value out of range is refused before the machine's state is looked at") {
  World w;
  w.homing_runs();
  // cmd.home_axes naming no axis (a request fault), and trend_cycles out of range, while a cycle runs.
  CHECK(reason_of(w.plan(Table::holding_register, kTrendCycles, {60000})) == RefusalReason::out_of_range);
  CHECK(reason_of(w.plan(Table::holding_register, kHomeAxes, {0})) == RefusalReason::no_axis_named);
}

TEST_CASE("plan_write: a command the machine cannot carry out now is refused before the settings lock") {
  World w;
  w.locked = true;
  w.status.interlocks |= homing::interlock::estop;
  // cmd.home_axes (X) and global.trend_cycles in one request: the command's refusal comes first.
  const auto p = w.plan(Table::holding_register, kHomeAxes, {1, 5});
  CHECK(reason_of(p) == RefusalReason::homing_blocked);
  CHECK(address_of(p) == kHomeAxes);
  CHECK(p.error().refusal.code == registers::ExceptionCode::server_device_failure);
}

TEST_CASE("plan_write: while a cycle runs the command register is refused before the setting beside it") {
  World w;
  w.homing_runs();
  const auto p = w.plan(Table::holding_register, kHomeAxes, {1, 5});
  CHECK(reason_of(p) == RefusalReason::busy);
  CHECK(address_of(p) == kHomeAxes);
  CHECK(p.error().refusal.message.find("cmd.home_axes") != std::string::npos);
}

TEST_CASE("plan_write: a wrong unlock code is refused and handed back to be counted, without counting it") {
  World w;
  w.locked = true;
  const auto p = w.plan(Table::holding_register, kUnlock, {1234});
  CHECK(reason_of(p) == RefusalReason::wrong_unlock_code);
  REQUIRE(p.error().wrong_unlock_code);
  CHECK(*p.error().wrong_unlock_code == 1234);
  CHECK(p.error().refusal.message.find("1 in a row") != std::string::npos);
  CHECK(w.guard.wrong_in_a_row() == 0);  // deciding counted nothing
}

TEST_CASE("plan_write: during a lockout every unlock is refused without being tried, the right code too") {
  World w;
  w.locked = true;
  for (std::uint32_t n = 1; n <= 5; ++n) w.guard.attempt(n, w.now);  // the fifth begins the lockout
  REQUIRE(w.guard.remaining(w.now) > 0s);
  const auto p = w.plan(Table::holding_register, kUnlock, {static_cast<std::uint16_t>(kCode)});
  CHECK(reason_of(p) == RefusalReason::unlock_locked_out);
  CHECK_FALSE(p.error().wrong_unlock_code);  // nothing to count: the code was not tried
  w.now += w.guard.remaining(w.now);
  const auto after = w.plan(Table::holding_register, kUnlock, {static_cast<std::uint16_t>(kCode)});
  REQUIRE(after.has_value());
  CHECK(after->unlock_code == kCode);
}

TEST_CASE("plan_write: the right unlock code plans the unlock and keeps no code in the host registers") {
  World w;
  w.locked = true;
  const auto p = w.plan(Table::holding_register, kUnlock, {static_cast<std::uint16_t>(kCode)});
  REQUIRE(p.has_value());
  CHECK(p->unlock_code == kCode);
  CHECK(p->accepted.host.unlock_code == 0);
  CHECK(p->stored.empty());
}

TEST_CASE("plan_write: without an unlock code an unlock is refused as no_unlock_code and handed back with nothing to count") {
  World w;
  w.guard = server::UnlockGuard{0, server::UnlockPolicy{}};
  const auto p = w.plan(Table::holding_register, kUnlock, {1234});
  CHECK(reason_of(p) == RefusalReason::no_unlock_code);
  CHECK(address_of(p) == kUnlock);
  CHECK_FALSE(p.error().wrong_unlock_code);
}

TEST_CASE("plan_write: without an unlock code cmd.lock_settings is refused as no_unlock_code, with one it is planned") {
  World w;
  const auto lock = registers::find_register("cmd.lock_settings")->address;
  CHECK(w.plan(Table::coil, lock, {1}).has_value());
  w.guard = server::UnlockGuard{0, server::UnlockPolicy{}};
  const auto p = w.plan(Table::coil, lock, {1});
  CHECK(reason_of(p) == RefusalReason::no_unlock_code);
  CHECK(address_of(p) == lock);
}

TEST_CASE("plan_write: a locked setting is refused before the wiring is asked") {
  World w;
  w.locked = true;
  w.wiring_refuses();
  const auto p = w.plan(Table::holding_register, kTrendCycles, {5});
  CHECK(reason_of(p) == RefusalReason::locked);
  CHECK(address_of(p) == kTrendCycles);
}

TEST_CASE("plan_write: settings the wiring cannot run are refused before a running cycle is") {
  World w;
  w.wiring_refuses();
  w.homing_runs();
  const auto p = w.plan(Table::holding_register, kTrendCycles, {5});
  CHECK(reason_of(p) == RefusalReason::wiring);
  CHECK(p.error().refusal.message.find("no GPIO line for it") != std::string::npos);
}

TEST_CASE("plan_write: a setting written while a homing cycle runs is refused as busy with the change in words") {
  World w;
  w.homing_runs();
  const auto p = w.plan(Table::holding_register, kTrendCycles, {5});
  CHECK(reason_of(p) == RefusalReason::busy);
  CHECK(p.error().refusal.code == registers::ExceptionCode::server_device_busy);
  CHECK(p.error().refusal.message.find("global.trend_cycles") != std::string::npos);
}

TEST_CASE("plan_write: an accepted setting plans its durable row, the first register it changes and nothing else") {
  World w;
  const auto p = w.plan(Table::holding_register, kTrendCycles, {5});
  REQUIRE(p.has_value());
  REQUIRE(p->stored.size() == 1);
  CHECK(p->stored[0].name == "global.trend_cycles");
  CHECK(p->stored[0].value == 5);
  CHECK(p->about == kTrendCycles);
  CHECK(p->accepted.settings.global.trend_cycles == 5);
  CHECK(p->effects.empty());
  CHECK_FALSE(p->unlock_code);
  CHECK(w.settings.global.trend_cycles == 20);  // the snapshot is untouched
}

TEST_CASE("plan_write: a new history length carries the effect its register row declares, an unchanged one none") {
  World w;
  const registers::Register* rows = registers::find_register("global.history_max_rows");
  REQUIRE(rows);
  CHECK(rows->effect == registers::Effect::history_limits);
  const auto changed = w.plan(Table::holding_register, rows->address, {0, 500});
  REQUIRE(changed.has_value());
  CHECK(changed->effects == std::vector<registers::Effect>{registers::Effect::history_limits});
  const auto same = w.plan(Table::holding_register, rows->address, {0, 10'000});  // the default
  REQUIRE(same.has_value());
  CHECK(same->effects.empty());
  CHECK(same->stored.empty());
}

TEST_CASE("plan_write: a heartbeat is planned as a host value, stored nowhere, even while locked and homing") {
  World w;
  w.locked = true;
  w.homing_runs();
  const auto p = w.plan(Table::holding_register, 20, {77});  // host.heartbeat
  REQUIRE(p.has_value());
  CHECK(p->accepted.host.heartbeat == 77);
  CHECK(p->stored.empty());
}

// ---- edit sessions (server/edit_sessions.hpp) ----

namespace {

constexpr std::uint16_t kEdit = 50;  // edit.command

registers::RawWrite staged(std::string_view name, std::int64_t raw) { return {registers::find_register(name), raw}; }

}  // namespace

TEST_CASE("plan_write: edit.command begins a session once, and not beyond the most sessions") {
  World w;
  const auto p = w.plan(Table::holding_register, kEdit, {1});
  REQUIRE(p.has_value());
  CHECK(p->edit == server::EditAction::begin);
  w.edit_state = server::EditState::open;
  CHECK(reason_of(w.plan(Table::holding_register, kEdit, {1})) == RefusalReason::edit_session_open);
  w.edit_state = server::EditState::none;
  w.edit_full = true;
  CHECK(reason_of(w.plan(Table::holding_register, kEdit, {1})) == RefusalReason::edit_sessions_full);
  w.edit_state = server::EditState::expired;  // an expired session begins again in its own place
  CHECK(w.plan(Table::holding_register, kEdit, {1})->edit == server::EditAction::begin);
}

TEST_CASE("plan_write: in an open session a setting is staged, even one its rules refuse alone, and nothing is planned to apply") {
  World w;
  w.edit_state = server::EditState::open;
  // 12000 mm/min alone breaks X's stop distance: staged, judged at the commit.
  const auto p = w.plan(Table::holding_register, registers::find_register("axis.x.seek_feedrate")->address, {12000});
  REQUIRE(p.has_value());
  CHECK(p->edit == server::EditAction::stage);
  REQUIRE(p->to_stage.size() == 1);
  CHECK(p->to_stage[0].raw == 12000);
  CHECK(p->stored.empty());
  CHECK(p->accepted.changes.empty());
  // Its range is still checked at once.
  CHECK(reason_of(w.plan(Table::holding_register, registers::find_register("axis.x.seek_feedrate")->address, {65000})) ==
        RefusalReason::out_of_range);
}

TEST_CASE("plan_write: in a session, settings are staged alone, not while locked, and never after the timeout") {
  World w;
  w.edit_state = server::EditState::open;
  CHECK(reason_of(w.plan(Table::holding_register, kHomeAxes, {1, 5})) == RefusalReason::edit_mixed);
  // The register named is the one that is no setting, not the first written.
  const auto skew = registers::find_register("axis.x.max_skew_change")->address;
  const auto mixed = w.plan(Table::holding_register, skew, {0, 100, 0, 7});
  REQUIRE(reason_of(mixed) == RefusalReason::edit_mixed);
  CHECK(mixed.error().refusal.address == registers::find_register("axis.x.target")->address);
  // A heartbeat alone is no setting: applied at once, session or not.
  const auto hb = w.plan(Table::holding_register, 20, {9});
  REQUIRE(hb.has_value());
  CHECK(hb->edit == server::EditAction::none);
  w.locked = true;
  CHECK(reason_of(w.plan(Table::holding_register, kTrendCycles, {5})) == RefusalReason::locked);
  w.locked = false;
  w.edit_state = server::EditState::expired;
  CHECK(reason_of(w.plan(Table::holding_register, kTrendCycles, {5})) == RefusalReason::edit_session_expired);
  CHECK(reason_of(w.plan(Table::holding_register, kEdit, {2})) == RefusalReason::edit_session_expired);
}

TEST_CASE("plan_write: a commit plans the staged set as one write, and its rules are judged over the whole set") {
  World w;
  w.edit_state = server::EditState::open;
  std::vector<registers::RawWrite> set{staged("axis.x.seek_feedrate", 12000), staged("axis.x.acceleration", 5000)};
  w.edit_staged = set;
  const auto p = w.plan(Table::holding_register, kEdit, {2});
  REQUIRE(p.has_value());
  CHECK(p->edit == server::EditAction::commit);
  CHECK(p->stored.size() == 2);
  CHECK(p->accepted.settings.axes[0].seek_feedrate_mm_per_min == 12000);
  // Without the acceleration the same feedrate breaks the stop-distance rule: refused, nothing planned.
  set.pop_back();
  w.edit_staged = set;
  const auto refused = w.plan(Table::holding_register, kEdit, {2});
  CHECK(reason_of(refused) == RefusalReason::rule);
  // A commit while a cycle runs is busy, as a direct write is.
  set.push_back(staged("axis.x.acceleration", 5000));
  w.edit_staged = set;
  w.homing_runs();
  CHECK(reason_of(w.plan(Table::holding_register, kEdit, {2})) == RefusalReason::busy);
}

TEST_CASE("plan_write: commit and discard without a session are refused, discard ends an expired one") {
  World w;
  CHECK(reason_of(w.plan(Table::holding_register, kEdit, {2})) == RefusalReason::edit_no_session);
  CHECK(reason_of(w.plan(Table::holding_register, kEdit, {3})) == RefusalReason::edit_no_session);
  w.edit_state = server::EditState::expired;
  CHECK(w.plan(Table::holding_register, kEdit, {3})->edit == server::EditAction::discard);
}

TEST_CASE("edit sessions: staged values by register, the later write winning, in address order, expired past the timeout") {
  server::EditSessions s;
  using T = server::EditSessions::Clock::time_point;
  const T t0{};
  const std::string hmi = "tcp 10.0.0.5:40000";
  CHECK(s.state(hmi) == server::EditState::none);
  REQUIRE(s.begin(hmi, t0) == server::EditSessions::Begun::begun);
  CHECK(s.begin(hmi, t0) == server::EditSessions::Begun::already_open);
  const registers::RawWrite later[] = {staged("axis.y.pull_off", 3000), staged("axis.x.pull_off", 2000)};
  s.stage(hmi, later, t0);
  const registers::RawWrite again[] = {staged("axis.x.pull_off", 2500)};
  s.stage(hmi, again, t0 + 50s);
  const auto set = s.staged(hmi);
  REQUIRE(set.size() == 2);
  CHECK(set[0].reg->name() == "axis.x.pull_off");
  CHECK(set[0].raw == 2500);
  CHECK(set[1].reg->name() == "axis.y.pull_off");
  CHECK(s.expire(t0 + 100s, 60s).empty());  // 50 s since its last write
  const auto gone = s.expire(t0 + 111s, 60s);
  REQUIRE(gone.size() == 1);
  CHECK(gone[0].owner == hmi);
  CHECK(gone[0].staged == 2);
  CHECK(s.state(hmi) == server::EditState::expired);
  CHECK(s.staged(hmi).empty());
  s.close(hmi);
  CHECK(s.state(hmi) == server::EditState::none);
}

TEST_CASE("edit sessions: at most 32 open at once, and a session belongs to its connection") {
  server::EditSessions s;
  const server::EditSessions::Clock::time_point t{};
  for (int i = 0; i < 32; ++i)
    REQUIRE(s.begin("tcp 10.0.0." + std::to_string(i) + ":1", t) == server::EditSessions::Begun::begun);
  CHECK(s.begin("tcp 10.0.1.1:1", t) == server::EditSessions::Begun::full);
  const server::ClientInfo a{1, server::Transport::tcp, "10.0.0.5:40000"}, b{2, server::Transport::tcp, "10.0.0.5:40001"};
  CHECK(server::EditSessions::owner_of(a) != server::EditSessions::owner_of(b));
}

TEST_CASE("plan_write: a refused block of registers is about the first setting it changes, not a move target before it") {
  // Found by an integrator: axis.x.target (160) was named, which is no
  // setting and is accepted alone during a cycle and while locked.
  const auto& skew = *registers::find_register("axis.x.max_skew_change");         // 158, unchanged
  const auto& target = *registers::find_register("axis.x.target");                // 160, changed
  const auto& following = *registers::find_register("axis.x.max_following_error");  // 162, changed
  REQUIRE(target.address == skew.address + 2);
  REQUIRE(following.address == target.address + 2);
  const auto w32 = [](std::int64_t v) {
    const auto u = static_cast<std::uint32_t>(v);
    return std::vector<std::uint16_t>{static_cast<std::uint16_t>(u >> 16), static_cast<std::uint16_t>(u & 0xFFFF)};
  };
  std::vector<std::uint16_t> block = w32(skew.default_raw);
  for (const auto v : w32(9000)) block.push_back(v);
  for (const auto v : w32(following.default_raw + 100)) block.push_back(v);
  SECTION("while a cycle runs") {
    World w;
    w.homing_runs();
    const auto p = w.plan(Table::holding_register, skew.address, block);
    CHECK(reason_of(p) == RefusalReason::busy);
    CHECK(address_of(p) == following.address);
  }
  SECTION("while settings are locked") {
    World w;
    w.locked = true;
    const auto p = w.plan(Table::holding_register, skew.address, block);
    CHECK(reason_of(p) == RefusalReason::locked);
    CHECK(address_of(p) == following.address);
    CHECK(p.error().refusal.message.find("security.unlock32 when above 65535") != std::string::npos);
  }
  SECTION("accepted") {
    World w;
    const auto p = w.plan(Table::holding_register, skew.address, block);
    REQUIRE(p.has_value());
    CHECK(p->about == following.address);
  }
}
