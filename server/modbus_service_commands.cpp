// ModbusService: the commands an accepted write carries (coils, cmd.home_axes)
// handed to the control loop, each logged with the client that sent it.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "modbus_service.hpp"
#include "registers/codec.hpp"
#include "registers/lookup.hpp"
#include "write_log.hpp"

namespace server {
namespace {

std::string_view command_name(registers::Command c) {
  using registers::Command;
  switch (c) {
    case Command::home_all: return "home_all";
    case Command::home_axis: return "home";
    case Command::abort: return "abort";
    case Command::reset_alarm: return "reset_alarm";
    case Command::jog_plus: return "jog_plus";
    case Command::jog_minus: return "jog_minus";
    case Command::move: return "move";
    case Command::homing_permit: return "homing_permit";
    case Command::lock_settings: return "lock_settings";
    case Command::home_axes: return "home_axes";
    case Command::unhome_axis: return "unhome";
    case Command::set_position: return "set_position";
    case Command::refcheck_axis: return "refcheck";
    case Command::measure_axis: return "measure";
  }
  return "?";
}

}  // namespace

// The jog coils of one write as buttons (jog_buttons.hpp), decided and handed
// to the loop under one lock: one jog per axis for the whole write, so that
// the loop never takes the first coil of an FC 15 of both alone, and no other
// client's decision lands between a decision and its hand-over (the lock
// order mutex_, then the loop's mailbox, as in disconnected()).
void ModbusService::press_jog_buttons(const std::vector<registers::CommandRequest>& commands,
                                      const ClientInfo& client) {
  using registers::Command;
  std::array<std::optional<std::int8_t>, homing::kAxisCount> jog{};
  std::unique_lock<std::shared_mutex> lock;
  for (const auto& r : commands) {
    if (r.command != Command::jog_plus && r.command != Command::jog_minus) continue;
    if (!lock.owns_lock()) lock = std::unique_lock(mutex_);
    const auto a = static_cast<std::size_t>(r.axis);
    if (auto j = jog_buttons_.write(a, r.command == Command::jog_plus ? 1 : -1, r.on, client.id)) jog[a] = j;
    host_.jog_plus[a] = jog_buttons_.held(a, 1);
    host_.jog_minus[a] = jog_buttons_.held(a, -1);
  }
  for (std::size_t a = 0; a < homing::kAxisCount; ++a)
    if (jog[a]) loop_.set_jog(a, *jog[a], client.id);
}

void ModbusService::run_commands(const std::vector<registers::CommandRequest>& commands, const ClientInfo& client) {
  using registers::Command;
  press_jog_buttons(commands, client);
  homing::Commands c{};
  bool any = false;
  for (const auto& r : commands) {
    const std::size_t a = r.axis >= 0 ? static_cast<std::size_t>(r.axis) : 0;
    switch (r.command) {
      case Command::home_all: c.home_all = true; any = true; break;
      case Command::home_axis: c.home_axes |= homing::axis_bit(a); any = true; break;
      case Command::home_axes: c.home_axes |= r.axes; any = true; break;
      case Command::unhome_axis: c.unhome_axes |= homing::axis_bit(a); any = true; break;
      case Command::refcheck_axis: c.refcheck_axes |= homing::axis_bit(a); any = true; break;
      case Command::measure_axis: c.measure_axes |= homing::axis_bit(a); any = true; break;
      case Command::abort: c.abort = true; any = true; break;
      case Command::reset_alarm:
        c.reset_alarm = true;
        any = true;
        if (store_ && store_->settings_lost()) acknowledge_settings_lost(client);
        break;
      case Command::jog_plus:
      case Command::jog_minus: {
        break;  // handed over with the write's other jog coils (press_jog_buttons)
      }
      case Command::move: {
        std::lock_guard lock(mutex_);
        c.move_axes |= homing::axis_bit(a);
        c.move_target_mm[a] = host_.target_mm[a];
        any = true;
        break;
      }
      case Command::set_position: {
        std::lock_guard lock(mutex_);
        c.set_position_axes |= homing::axis_bit(a);
        c.set_position_mm[a] = host_.target_mm[a];
        position_set_by_[a] = source_of(client);
        any = true;
        break;
      }
      case Command::homing_permit: loop_.set_permit_coil(r.on); break;
      case Command::lock_settings: {
        std::lock_guard lock(mutex_);
        locked_ = config_.unlock_code != 0;
        extras_.settings_locked = locked_;
        break;
      }
    }
    const bool held = r.command == Command::jog_plus || r.command == Command::jog_minus ||
                      r.command == Command::homing_permit;
    std::string axes = r.axis >= 0 ? "." + std::string(homing::kAxisLetters[a]) : std::string();
    for (std::size_t n = 0; n < homing::kAxisCount; ++n)
      if (r.axes & homing::axis_bit(n)) axes += " " + std::string(homing::kAxisLetters[n]);
    spdlog::info("command from {} {}: {}{}{}", client.transport, client.address, command_name(r.command), axes,
                 held ? (r.on ? " on" : " off") : "");
  }
  if (any) loop_.submit(c, true);
}

std::optional<registers::Refusal> ModbusService::command(const registers::Register& coil, bool on,
                                                         const ClientInfo& client) {
  const std::uint16_t address = coil.address;
  const std::uint8_t pdu[] = {0x05, static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address & 0xFF),
                              static_cast<std::uint8_t>(on ? 0xFF : 0x00), 0x00};
  refused_here_.reset();
  const Reply reply = handle(config_.unit_id, pdu, client);
  if (!reply.pdu.empty() && (reply.pdu[0] & 0x80) == 0) return std::nullopt;
  if (refused_here_) return refused_here_;
  registers::Refusal r;  // answered without a refusal record: say what the answer was
  r.code = reply.pdu.size() >= 2 ? static_cast<registers::ExceptionCode>(reply.pdu[1]) : registers::ExceptionCode::server_device_failure;
  r.message = "the module answered with exception " + std::string(registers::exception_name(r.code));
  r.address = address;
  return r;
}

// Lost settings are acknowledged only by a reset the engine takes: one
// refused for a cause still present leaves the flag, so the alarm comes back
// after a restart until a reset is really taken. Judged as the engine will
// judge it: on the causes the last period showed, the heartbeat's on the
// live heartbeat as the engine reads it (homingctl writes the heartbeat just
// before its reset; a watchdog may expire after the last period). A failed cycle winding down (the engine's
// other refusal) cannot run while settings are lost: their alarm blocks every
// cycle.
void ModbusService::acknowledge_settings_lost(const ClientInfo& client) {
  std::uint16_t interlocks = loop_.status().interlocks;
  std::unique_lock lock(mutex_);
  if (loop_.heartbeat_fresh(settings_.global.watchdog_ms))
    interlocks &= static_cast<std::uint16_t>(~homing::interlock::communication_lost);
  else
    interlocks |= homing::interlock::communication_lost;
  const homing::CommandResult judged = homing::reset_refusal_of(interlocks);
  if (judged == homing::CommandResult::accepted) {
    (void)store_->acknowledge_settings_lost(source_of(client));
    return;
  }
  lock.unlock();
  spdlog::warn("'settings lost' not acknowledged by {} {}: the reset is refused ({}); clear the cause and reset again",
               client.transport, client.address, homing::command_result_name(judged));
}

void ModbusService::audit_position_set(std::size_t axis, double old_mm, double new_mm) {
  static const auto name = [](std::size_t a) { return fmt::format("axis.{}.position", homing::kAxisLetters[a]); };
  const registers::Register* reg = registers::find_register(name(axis));
  persistence::ChangeSource source;
  {
    std::lock_guard lock(mutex_);
    source = position_set_by_[axis];
  }
  // The audit row first: once the log says it, the row is there.
  if (store_ && reg) {
    const persistence::Change change{name(axis), registers::to_raw(*reg, old_mm), registers::to_raw(*reg, new_mm)};
    if (auto r = store_->audit(change, source); !r)
      spdlog::error("the coordinate of {} set by hand was not audited: {}", homing::kAxisUpper[axis], r.error().message);
  }
  spdlog::warn("{} set by hand from {:.3f} to {:.3f} by {} {} (the axis stays unhomed)", homing::kAxisUpper[axis], old_mm,
               new_mm, source.transport, source.client);
}

}  // namespace server
