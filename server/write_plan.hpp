#pragma once
// A write to the module unit, decided before anything happens: plan_write
// looks at one request against one snapshot of everything the answer depends
// on (settings, host registers, the machine's status, the client, the lock
// and its guard, the wiring) and returns either the refusal (reason,
// exception, register) or the plan; ModbusService::write_module then carries
// the plan out. So no refusal ever follows an effect: a right unlock code
// opens the lock only once every other check has passed, and the one failure
// left to the carrying out, the durable commit, comes before every other
// effect (a failed commit changes nothing).
//
// The checks, in this order (the first that fails answers):
//  1. client_read_only: the client is not in --write-allow
//  2. role: the client's certificate role does not grant the write
//  3. the request itself (registers::validate_write): addresses and access
//     (02), 32-bit halves, ranges, a gantry slave's inherited settings, the
//     engine's configuration rules (03)
//  4. a command register the machine cannot carry out now (refusal_now: 06, 04)
//  5. the unlock code it carries: every unlock refused during a lockout,
//     a wrong code (the only refusal with an effect: the guard counts it)
//  6. locked: it changes settings while they stay locked
//  7. wiring: the machine behind cannot run the new settings
//  8. busy: it changes settings while a homing cycle runs
//
// An edit session (server/edit_sessions.hpp) changes what a settings write
// means: edit.command is decided here too (begin, commit, discard), and while
// the client's session is open its settings writes are planned as staged
// (checks 1 to 3's ranges, then the lock), their rules and the rest checked
// over the whole staged set at the commit.
#include <chrono>
#include <cstdint>
#include <expected>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "homing/settings.hpp"
#include "homing/status.hpp"
#include "persistence/settings_store.hpp"
#include "registers/validate.hpp"
#include "edit_sessions.hpp"
#include "request_handler.hpp"
#include "unlock_guard.hpp"

namespace server {

// What the machine behind can run (GPIO wiring): why not, or nullopt.
using MachineCheck = std::function<std::optional<std::string>(const homing::Settings&)>;

// Everything a write's answer depends on, taken once per request.
struct WriteState {
  const homing::Settings& settings;
  const registers::HostRegisters& host;
  const homing::Status& status;  // the one machine snapshot of this request
  registers::WordOrder order = registers::WordOrder::high_first;
  bool client_may_write = true;  // --write-allow
  bool locked = false;           // settings locked (--unlock-code)
  const UnlockGuard& unlock_guard;
  UnlockGuard::Clock::time_point now;
  const MachineCheck* machine_check = nullptr;  // null: the machine runs anything
  // The client's edit session: its state, what it staged, whether another may begin.
  EditState edit_state = EditState::none;
  std::span<const registers::RawWrite> edit_staged{};
  bool edit_sessions_full = false;
  bool broadcast = false;  // an RTU broadcast: no edit session, settings apply at once
};

enum class EditAction : std::uint8_t {
  none,     // no edit session involved: applied as planned
  begin,    // the client's session begins
  stage,    // settings staged into the open session (to_stage), nothing applied
  commit,   // the staged set, planned as one write, is applied and the session ends
  discard,  // the session (open or expired) ends, nothing applied
};

struct WritePlan {
  registers::AcceptedWrite accepted;  // settings, host registers and commands with the request applied
  // The right unlock code it carries: the lock opens (and the guard forgets
  // earlier wrong codes) once the commit, if any, has succeeded.
  std::optional<std::uint32_t> unlock_code;
  // The persisted settings it changes, committed before any other effect.
  std::vector<persistence::SettingWrite> stored;
  std::uint16_t about = 0;  // the first register it changes: a failed commit names it
  std::string changes;      // what it changes, in words, for the log and a failed commit
  // The effects declared on the rows it changes (registers::Effect), each once.
  std::vector<registers::Effect> effects;
  EditAction edit = EditAction::none;
  std::vector<registers::RawWrite> to_stage;  // EditAction::stage
};

struct PlannedRefusal {
  registers::Refusal refusal;
  // A wrong unlock code: the guard counts it (the refusal's only effect).
  std::optional<std::uint32_t> wrong_unlock_code;
};

std::expected<WritePlan, PlannedRefusal> plan_write(registers::Table table, std::uint16_t start,
                                                    std::span<const std::uint16_t> values, const ClientInfo& client,
                                                    const WriteState& state);

// Checks 3 (after the decoding: slave inheritance and rules) to 8 for writes
// already decoded and range-checked, in address order: an edit session's
// staged settings at its commit. `start` names the request where a refusal
// is about no register of its own.
std::expected<WritePlan, PlannedRefusal> plan_decoded_write(std::span<const registers::RawWrite> writes,
                                                            std::uint16_t start, const WriteState& state);

// Checks 1 and 2 alone, for writes to the simulator unit.
std::optional<registers::Refusal> client_refusal(registers::Unit unit, registers::Table table, std::uint16_t start,
                                                 std::size_t count, const ClientInfo& client, bool client_may_write);

}  // namespace server
