// ModbusService: the write path of the module unit. Each write is decided
// whole first (server/write_plan.hpp), then carried out. Writes that arrive
// together are decided one after the other by whichever of their threads
// leads (the settings writer for those taken later, modbus_service_writer.cpp),
// and the settings they change are committed together in one SQLite
// transaction (group commit: one fsync for all of them); each is answered
// only once the commit that holds it is durable, and none is applied before.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "frame_changes.hpp"
#include "modbus_service.hpp"
#include "registers/lookup.hpp"
#include "write_log.hpp"
#include "write_ticket.hpp"

namespace server {

std::optional<Reply> ModbusService::write_module(std::uint8_t fc, registers::Table table, std::uint16_t start,
                                                 std::span<const std::uint16_t> values, const ClientInfo& client) {
  WriteTicket t{table, start, values, client, std::nullopt, {}, false, false, {}, nullptr};
  {
    std::unique_lock lock(batch_mutex_);
    // Reserved by handle_now(): this request alone, at once, so that
    // nothing queued meanwhile is committed on its (event loop's) thread.
    const bool reserved = reserved_for_ == std::this_thread::get_id();
    if (reserved) {
      reserved_for_.reset();
      t.lead = true;
    } else {
      batch_queue_.push_back(&t);
      if (!batch_leader_) batch_leader_ = t.lead = true;
      t.wake.wait(lock, [&t] { return t.done || t.lead; });
    }
    if (!t.done) lead(lock, reserved ? &t : nullptr);
  }
  // Answered on this thread: refuse() records the refusal for this request.
  if (t.refusal) return refuse(fc, *t.refusal, client);
  run_commands(t.commands, client);
  return std::nullopt;
}

std::optional<Reply> ModbusService::handle_now(std::uint8_t unit, std::span<const std::uint8_t> pdu,
                                               const ClientInfo& client) {
  if (!needs_nothing_durable(unit, pdu, client)) return std::nullopt;
  {
    std::lock_guard lock(batch_mutex_);
    if (batch_leader_ || !batch_queue_.empty()) return std::nullopt;  // it would wait for that batch
    batch_leader_ = true;  // held for this request: no batch starts before it
    reserved_for_ = std::this_thread::get_id();
  }
  Reply reply = handle(unit, pdu, client);
  {
    // A request refused before the write path (a bad address...) leaves the reservation.
    std::lock_guard lock(batch_mutex_);
    if (reserved_for_ == std::this_thread::get_id()) {
      reserved_for_.reset();
      pass_lead();
    }
  }
  return reply;
}

void ModbusService::lead(std::unique_lock<std::mutex>& lock, WriteTicket* reserved) {
  // Every write queued so far, or the reserved one alone.
  std::vector<WriteTicket*> batch;
  if (reserved) batch.push_back(reserved);
  else batch.swap(batch_queue_);
  lock.unlock();
  const bool loop_to_wake = process_batch(batch);
  lock.lock();
  // Under the lock: a waiting ticket lives on its thread's stack, gone once
  // that thread sees done and returns.
  std::vector<WriteTicket*> later;
  for (WriteTicket* w : batch) {
    w->done = true;
    if (w->later) later.push_back(w);
    else w->wake.notify_one();
  }
  pass_lead();
  lock.unlock();
  for (WriteTicket* w : later) answer_later(*w->later);
  // After the answers are on their way: the period the new settings wake
  // would otherwise take a core from the event loop that sends them.
  if (loop_to_wake) loop_.wake_for_news();
  lock.lock();
}

void ModbusService::pass_lead() {
  batch_leader_ = !batch_queue_.empty();
  if (!batch_leader_) return;
  WriteTicket& next = *batch_queue_.front();
  if (next.later) {
    writer_leads_ = true;
    writer_wake_.notify_one();
    return;
  }
  next.lead = true;
  next.wake.notify_one();
}

// A plain write (FC 05, 06, 15, 16) to the module unit whose registers are
// none of them a setting nor the edit session's command, nor the reset that
// acknowledges lost settings: its plan stores nothing, so it never waits for
// a commit.
bool ModbusService::needs_nothing_durable(std::uint8_t unit, std::span<const std::uint8_t> pdu,
                                          const ClientInfo& client) const {
  if (pdu.empty()) return false;
  const bool module = unit == config_.unit_id || (over_network(client.transport) && (unit == 0 || unit == 0xFF));
  if (!module) return false;
  const auto request = decode_request(pdu);
  if (!request) return false;
  const auto* w = std::get_if<WriteRequest>(&request->body);
  if (!w) return false;
  for (const registers::Register& r :
       registers::registers_overlapping(registers::Unit::module, w->table, w->start, w->values.size())) {
    if (r.persisted || r.key == registers::Key::edit_command) return false;
    // The reset that acknowledges lost settings commits that acknowledgement.
    if (r.key == registers::Key::cmd_reset_alarm && store_ && store_->settings_lost()) return false;
  }
  return true;
}

// The plans that change settings wait for the commit; every other plan
// (commands, the heartbeat, the unlock code, an edit session's begin, stage
// or discard) is carried out at once: writes that arrive together have no
// order among them, and none of these has anything to make durable.
bool ModbusService::process_batch(const std::vector<WriteTicket*>& batch) {
  struct Durable {
    WriteTicket* ticket;
    WritePlan plan;
    std::string owner;
  };
  std::vector<Durable> durable;
  durable.reserve(batch.size());  // a plan holds the settings: no reallocation moves them
  {
    std::lock_guard lock(mutex_);
    expire_edit_sessions();
    homing::Settings planned = settings_;  // with the settings of the durable plans decided so far
    registers::HostRegisters planned_host = host_;
    for (WriteTicket* t : batch) {
      homing::Status status = loop_.status();  // one machine snapshot per request
      // The snapshot is up to a period old (50 ms idle): a heartbeat written
      // since (this request's, or the one just before a cmd.home_axes, as a
      // PLC's next scan or homingctl writes it) has already cleared what the
      // engine will judge the start on, the live heartbeat.
      if ((status.interlocks & homing::interlock::communication_lost) &&
          loop_.heartbeat_fresh(settings_.global.watchdog_ms))
        status.interlocks &= static_cast<std::uint16_t>(~homing::interlock::communication_lost);
      const std::string owner = EditSessions::owner_of(t->client);
      const std::vector<registers::RawWrite> staged = edits_.staged(owner);
      const WriteState state{.settings = planned,
                             .host = planned_host,
                             .status = status,
                             .order = config_.word_order,
                             .client_may_write = may_write(t->client),
                             .locked = locked_,
                             .unlock_guard = unlock_guard_,
                             .now = now(),
                             .machine_check = &config_.machine_check,
                             .edit_state = t->client.broadcast ? EditState::none : edits_.state(owner),
                             .edit_staged = staged,
                             .edit_sessions_full = edits_.open_count() >= EditSessions::kMaxSessions,
                             .broadcast = t->client.broadcast};
      auto plan = plan_write(t->table, t->start, t->values, t->client, state);
      if (!plan) {
        if (plan.error().wrong_unlock_code) count_wrong_unlock_code(*plan.error().wrong_unlock_code, t->client);
        if (state.edit_state == EditState::open) edits_.touch(owner, now());  // a refused commit keeps the session
        t->refusal = std::move(plan.error().refusal);
        continue;
      }
      if (!plan->stored.empty()) {
        planned = plan->accepted.settings;
        planned_host = plan->accepted.host;
        durable.push_back({t, std::move(*plan), owner});
        continue;
      }
      carry_out(*t, *plan, owner, staged.size());
      planned_host = plan->accepted.host;
    }
  }
  if (durable.empty()) return false;

  // One transaction for all of them, outside the lock: reads go on meanwhile
  // (they see the settings in force), and no other write is decided until
  // this batch is carried out (this thread leads until then).
  std::optional<persistence::Error> failed;
  if (store_) {
    std::vector<persistence::SettingsStore::BatchEntry> entries;
    for (const Durable& d : durable) entries.push_back({&d.plan.stored, source_of(d.ticket->client)});
    if (auto committed = store_->commit_batch(entries); !committed) failed = committed.error();
  }

  std::optional<homing::Settings> for_the_loop;
  {
    std::lock_guard lock(mutex_);
    for (Durable& d : durable) {
      if (failed) {
        if (edits_.state(d.owner) == EditState::open) edits_.touch(d.owner, now());
        d.ticket->refusal = registers::Refusal::because(registers::RefusalReason::storage_failed, d.plan.about,
                                                        "settings not stored: " + failed->message + "; " +
                                                            d.plan.changes);
        continue;
      }
      carry_out(*d.ticket, d.plan, d.owner, edits_.staged_count(d.owner));
    }
    if (!failed) for_the_loop = settings_;
  }
  // Handed over outside mutex_ and before the lead passes: a command decided
  // after this batch finds them in the loop's mailbox. The wake-up that makes
  // the loop publish them comes from lead(), once the answers are sent off.
  if (!for_the_loop) return false;
  loop_.set_settings(std::move(*for_the_loop), false);
  return true;
}

// Under mutex_: the effects of a plan, in this order: the edit session, the
// lock, the settings and what their rows declare, the host registers; the
// commands go back to the request's thread.
void ModbusService::carry_out(WriteTicket& t, WritePlan& plan, const std::string& owner, std::size_t staged) {
  const ClientInfo& client = t.client;
  switch (plan.edit) {
    case EditAction::none: break;
    case EditAction::begin:
      edits_.begin(owner, now());
      spdlog::info("edit session of {} begun: settings written from now are staged until its commit", owner);
      return;
    case EditAction::stage: edits_.stage(owner, plan.to_stage, now()); return;
    case EditAction::discard:
      spdlog::info("edit session of {} discarded by its client ({} staged settings dropped)", owner, staged);
      edits_.close(owner);
      return;
    case EditAction::commit:
      edits_.close(owner);
      spdlog::info("edit session of {} committed: {} staged settings, {} changed", owner, staged, plan.stored.size());
      break;
  }
  if (plan.unlock_code) unlock(*plan.unlock_code, client);
  if (plan.accepted.changes_persisted()) {
    const std::vector<std::string> lost = references_lost(settings_, plan.accepted.settings, loop_.status());
    settings_ = plan.accepted.settings;  // the control loop gets them once the batch is carried out
    for (const registers::Effect e : plan.effects) apply_effect(e);
    spdlog::info("settings changed by {} {}: {}", client.transport, client.address, plan.changes);
    for (const std::string& line : lost) spdlog::warn("{} (settings changed by {} {})", line, client.transport, client.address);
  }
  // Only the host values this request wrote: another client's, carried out
  // since this plan was decided, stay.
  const std::uint16_t old_heartbeat = host_.heartbeat;
  for (const registers::Change& c : plan.accepted.changes)
    if (!c.reg->persisted && c.reg->key != registers::Key::security_unlock) registers::set_host_raw(host_, *c.reg, c.new_raw);
  if (host_.heartbeat != old_heartbeat) loop_.heartbeat_written(host_.heartbeat);
  t.commands = std::move(plan.accepted.commands);
}

// Under mutex_: sessions left longer than global.edit_timeout_s end, logged.
void ModbusService::expire_edit_sessions() {
  const std::chrono::seconds timeout{settings_.global.edit_timeout_s};
  for (const EditSessions::Expired& e : edits_.expire(now(), timeout))
    spdlog::warn("edit session of {} discarded: no write or commit for {} s (global.edit_timeout_s); its {} staged "
                 "settings were not applied, and its settings writes are refused until it begins again or discards",
                 e.owner, timeout.count(), e.staged);
}

void ModbusService::flush_edit_sessions() {
  std::lock_guard lock(mutex_);
  expire_edit_sessions();
}

// Under mutex_: what a changed setting's row declares beyond the setting.
void ModbusService::apply_effect(registers::Effect effect) {
  switch (effect) {
    case registers::Effect::none: return;
    case registers::Effect::history_limits:
      if (!store_) return;
      if (auto r = store_->set_limits(settings_.global.history_max_rows, settings_.global.history_max_rows); !r)
        spdlog::warn("history limit not applied: {}", r.error().message);
      return;
  }
}

// Under mutex_: a wrong code the plan refused, counted by the guard.
void ModbusService::count_wrong_unlock_code(std::uint32_t code, const ClientInfo& client) {
  const UnlockGuard::Outcome outcome = unlock_guard_.attempt(code, now());
  if (outcome.lockout_started)
    spdlog::warn("security.unlock: {} wrong unlock codes in a row, the last from {} {}{}{}: every unlock is refused "
                 "for {} s (status.unlock_lockout_s), longer with each further wrong code up to "
                 "--unlock-lockout-max-s",
                 outcome.wrong_in_a_row, client.transport, client.address, client.identity.empty() ? "" : " ",
                 client.identity, outcome.lockout.count());
}

// Under mutex_: the right code, once the rest of its request has passed.
void ModbusService::unlock(std::uint32_t code, const ClientInfo& client) {
  (void)unlock_guard_.attempt(code, now());  // clears the count of wrong codes
  if (locked_)
    spdlog::info("settings unlocked by {} {}{}{}", client.transport, client.address, client.identity.empty() ? "" : " ",
                 client.identity);
  locked_ = false;
  extras_.settings_locked = false;
}

}  // namespace server
