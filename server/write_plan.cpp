#include "write_plan.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "client_role.hpp"
#include "registers/lookup.hpp"
#include "write_log.hpp"

namespace server {
namespace {

using registers::Refusal;
using registers::RefusalReason;

std::unexpected<PlannedRefusal> refused(Refusal r) { return std::unexpected(PlannedRefusal{std::move(r), {}}); }

// The register a security.unlock(32) value came in, for the refusal.
std::uint16_t unlock_address(const registers::AcceptedWrite& w, std::uint16_t start) {
  for (const registers::Change& c : w.changes)
    if (c.reg->key == registers::Key::security_unlock) return c.reg->address;
  return start;
}

// 5: the unlock code the request carries. Judged whether or not settings are
// locked, so that a code is never tried for free.
std::optional<PlannedRefusal> unlock_refusal(std::uint32_t code, std::uint16_t address, const WriteState& state) {
  // No code to guess: nothing counted, and an answer that says why.
  if (!state.unlock_guard.configured())
    return PlannedRefusal{Refusal::because(RefusalReason::no_unlock_code, address,
                                           "security.unlock written, but homingd runs without an unlock code "
                                           "(--unlock-code): settings are not locked, nothing was unlocked or counted"),
                          std::nullopt};
  const UnlockGuard::Outcome outcome = state.unlock_guard.judge(code, state.now);
  switch (outcome.verdict) {
    case UnlockVerdict::right: return std::nullopt;
    case UnlockVerdict::locked_out:
      return PlannedRefusal{
          Refusal::because(RefusalReason::unlock_locked_out, address,
                           fmt::format("{} wrong unlock codes in a row: every unlock is refused for {} s more "
                                       "(status.unlock_lockout_s); the code written was not tried, settings stay "
                                       "locked",
                                       outcome.wrong_in_a_row, state.unlock_guard.remaining(state.now).count())),
          std::nullopt};
    case UnlockVerdict::wrong:
      return PlannedRefusal{
          Refusal::because(RefusalReason::wrong_unlock_code, address,
                           fmt::format("wrong unlock code ({} in a row); settings stay locked",
                                       outcome.wrong_in_a_row)),
          code};
  }
  return std::nullopt;
}

// edit.command: begin, commit or discard this client's session. The row
// stands alone in the map, so the request holds nothing else.
std::expected<WritePlan, PlannedRefusal> plan_edit_command(const registers::RawWrite& w, const WriteState& state) {
  const std::uint16_t address = w.reg->address;
  WritePlan plan;
  switch (w.raw) {
    case 1:  // begin
      if (state.edit_state == EditState::open)
        return refused(Refusal::because(RefusalReason::edit_session_open, address,
                                        "edit.command = begin: this client's edit session is already open; commit "
                                        "(2) or discard (3) it first"));
      if (state.edit_state == EditState::none && state.edit_sessions_full)
        return refused(Refusal::because(RefusalReason::edit_sessions_full, address,
                                        fmt::format("edit.command = begin: {} edit sessions are open, the most",
                                                    EditSessions::kMaxSessions)));
      plan.edit = EditAction::begin;
      return plan;
    case 2: {  // commit
      if (state.edit_state == EditState::none)
        return refused(Refusal::because(RefusalReason::edit_no_session, address,
                                        "edit.command = commit: no edit session is open for this client; nothing "
                                        "was written"));
      if (state.edit_state == EditState::expired)
        return refused(Refusal::because(RefusalReason::edit_session_expired, address,
                                        "edit.command = commit: this client's edit session timed out "
                                        "(global.edit_timeout_s) and its staged settings were discarded; nothing "
                                        "was written"));
      auto committed = plan_decoded_write(state.edit_staged, address, state);
      if (!committed) return committed;
      committed->edit = EditAction::commit;
      return committed;
    }
    case 3:  // discard
      if (state.edit_state == EditState::none)
        return refused(Refusal::because(RefusalReason::edit_no_session, address,
                                        "edit.command = discard: no edit session is open for this client"));
      plan.edit = EditAction::discard;
      return plan;
    default: return plan;  // 0: nothing
  }
}

// A settings write while the client's session is open: range-checked (done),
// staged alone, refused while settings are locked or after the session timed out.
std::expected<WritePlan, PlannedRefusal> plan_staging(std::span<const registers::RawWrite> writes,
                                                      const WriteState& state) {
  const registers::Register& first =
      *std::find_if(writes.begin(), writes.end(), [](const auto& w) { return w.reg->persisted; })->reg;
  const std::uint16_t about = first.address;
  if (state.edit_state == EditState::expired)
    return refused(Refusal::because(RefusalReason::edit_session_expired, about,
                                    fmt::format("{}: this client's edit session timed out (global.edit_timeout_s) "
                                                "and its staged settings were discarded; begin again (edit.command "
                                                "= 1) or discard (3); nothing was written",
                                                first.name())));
  // A host value the request only carries along unchanged (a tool's block
  // filling a gap between two settings) is no effect; anything else is.
  const auto carried_along = [&](const registers::RawWrite& w) {
    return !registers::command_of(*w.reg, w.raw) && w.reg->key != registers::Key::security_unlock &&
           registers::host_raw(state.host, *w.reg) == w.raw;
  };
  for (const registers::RawWrite& w : writes)
    if (!w.reg->persisted && !carried_along(w))
      return refused(Refusal::because(RefusalReason::edit_mixed, w.reg->address,
                                      fmt::format("{} is no setting: in an edit session settings are staged alone, "
                                                  "write it in its own request; nothing was written",
                                                  w.reg->name())));
  if (state.locked)
    return refused(Refusal::because(RefusalReason::locked, about,
                                    fmt::format("settings are locked (write the unlock code to security.unlock, or to security.unlock32 when above 65535): {} "
                                                "not staged",
                                                first.name())));
  WritePlan plan;
  plan.edit = EditAction::stage;
  for (const registers::RawWrite& w : writes)
    if (w.reg->persisted) plan.to_stage.push_back(w);
  plan.about = about;
  return plan;
}

}  // namespace

std::optional<Refusal> client_refusal(registers::Unit unit, registers::Table table, std::uint16_t start,
                                      std::size_t count, const ClientInfo& client, bool client_may_write) {
  if (!client_may_write)
    return Refusal::because(RefusalReason::client_read_only, start,
                            fmt::format("{} is not in --write-allow; nothing was written", client.address));
  if (auto why = access_refusal(client, unit, table, start, count))
    return Refusal::because(RefusalReason::role, start, *why + "; nothing was written");
  return std::nullopt;
}

std::expected<WritePlan, PlannedRefusal> plan_write(registers::Table table, std::uint16_t start,
                                                    std::span<const std::uint16_t> values, const ClientInfo& client,
                                                    const WriteState& state) {
  if (auto r = client_refusal(registers::Unit::module, table, start, values.size(), client, state.client_may_write))
    return refused(std::move(*r));
  auto decoded =
      registers::decode_write(registers::Unit::module, table, start, values, state.order, registers::kinds_of(state.settings));
  if (!decoded) return refused(std::move(decoded.error()));
  for (const registers::RawWrite& w : *decoded)
    if (w.reg->key == registers::Key::edit_command) {
      if (state.broadcast)
        return refused(registers::Refusal::because(registers::RefusalReason::edit_broadcast, w.reg->address,
                                                   "edit.command in an RTU broadcast: no answer could say how it "
                                                   "went; address the module's unit id"));
      return plan_edit_command(w, state);
    }
  const bool settings = std::any_of(decoded->begin(), decoded->end(), [](const auto& w) { return w.reg->persisted; });
  if (settings && state.edit_state != EditState::none) return plan_staging(*decoded, state);
  return plan_decoded_write(*decoded, start, state);
}

std::expected<WritePlan, PlannedRefusal> plan_decoded_write(std::span<const registers::RawWrite> writes,
                                                            std::uint16_t start, const WriteState& state) {
  auto accepted = registers::validate_raw_writes(writes, state.settings, state.host);
  if (!accepted) return refused(std::move(accepted.error()));
  if (auto r = registers::refusal_now(*accepted, state.status)) return refused(std::move(*r));
  // A lock that cannot lock: an HMI's "lock" button would otherwise seem to protect the settings.
  for (const registers::CommandRequest& c : accepted->commands)
    if (c.command == registers::Command::lock_settings && c.on && !state.unlock_guard.configured())
      return refused(Refusal::because(RefusalReason::no_unlock_code, registers::find_register("cmd.lock_settings")->address,
                                      "cmd.lock_settings written, but homingd runs without an unlock code "
                                      "(--unlock-code): settings cannot be locked; nothing was locked"));

  WritePlan plan;
  bool unlocks = false;
  if (const std::uint32_t code = accepted->host.unlock_code; code != 0) {
    accepted->host.unlock_code = 0;  // a code is never kept (security.unlock reads 0)
    if (auto r = unlock_refusal(code, unlock_address(*accepted, start), state)) return std::unexpected(std::move(*r));
    plan.unlock_code = code;
    unlocks = true;
  }
  if (accepted->changes_persisted()) {
    // The setting the refusal is about: a move target or heartbeat written in
    // the same request is no setting, and an HMI marks the register named.
    const auto first_setting = std::find_if(accepted->changes.begin(), accepted->changes.end(),
                                            [](const registers::Change& c) { return c.reg->persisted; });
    plan.about = first_setting != accepted->changes.end() ? first_setting->reg->address : start;
    plan.changes = describe_changes(accepted->changes, registers::kinds_of(accepted->settings));
    if (state.locked && !unlocks)
      return refused(Refusal::because(RefusalReason::locked, plan.about,
                                      "settings are locked (write the unlock code to security.unlock, or to security.unlock32 when above 65535): " +
                                          plan.changes));
    if (state.machine_check && *state.machine_check) {
      if (auto problem = (*state.machine_check)(accepted->settings))
        return refused(Refusal::because(RefusalReason::wiring, plan.about,
                                        "the machine's wiring cannot do it: " + *problem + "; " + plan.changes));
    }
    if (state.status.homing)
      return refused(Refusal::because(RefusalReason::busy, plan.about, "a homing cycle runs: " + plan.changes));
    for (const registers::Change& c : accepted->changes) {
      if (!c.reg->persisted) continue;
      plan.stored.push_back({c.reg->name(), c.new_raw});
      if (c.reg->effect != registers::Effect::none &&
          std::find(plan.effects.begin(), plan.effects.end(), c.reg->effect) == plan.effects.end())
        plan.effects.push_back(c.reg->effect);
    }
  }
  plan.accepted = std::move(*accepted);
  return plan;
}

}  // namespace server
