// ModbusService: the simulator unit (--sim-unit), read from a snapshot and
// written on the live simulator inside the control loop.
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "modbus_service.hpp"
#include "registers/sim_bindings.hpp"
#include "write_log.hpp"

namespace server {
namespace {

using registers::Table;

registers::SimReadback readback_of(const homing::sim::SimulatorView& sim) {
  registers::SimReadback r;
  for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
    r.actual_position_mm[a] = sim.axes[a].actual_position_mm;
    r.sensor[a] = sim.axes[a].sensor;
    r.at_hard_stop[a] = sim.axes[a].at_hard_stop;
    r.driven_by[a] = sim.axes[a].driven_by;
    r.indexer_locked[a] = sim.axes[a].indexer_locked;
    r.limit_min[a] = sim.axes[a].limit_min;
    r.limit_max[a] = sim.axes[a].limit_max;
  }
  return r;
}

registers::SimSwitches switches_of(const homing::sim::SimulatorView& sim) {
  return registers::SimSwitches{sim.estop, sim.start_button};
}

}  // namespace

std::int64_t ModbusService::sim_raw(const registers::Register& reg, const Snapshot& snap) const {
  return registers::sim_raw(reg, snap.sim.config, switches_of(snap.sim), readback_of(snap.sim));
}

std::optional<Reply> ModbusService::write_sim(std::uint8_t fc, Table table, std::uint16_t start,
                                              std::span<const std::uint16_t> values, const ClientInfo& client) {
  // A carriage's values in the unit of its axis's kind (the module's settings).
  const registers::AxisKinds kinds = registers::kinds_of(settings());
  // Address, access and range need no machine: refused here at once.
  if (auto decoded =
          registers::decode_write(registers::Unit::simulator, table, start, values, config_.word_order, kinds);
      !decoded)
    return refuse(fc, decoded.error(), client);
  // The rest is decided and applied on the live simulator inside the control
  // loop (never on a snapshot that may miss the previous write), and answered
  // once a snapshot shows it: an acknowledged write holds and reads back.
  std::optional<registers::Refusal> refused;
  const registers::Register* busy_reg = nullptr;
  std::vector<registers::Change> changes;
  const ControlLoop::SimEdit edit = [&](homing::sim::SimulatorControls& sim, const homing::Outputs& next) {
    const homing::sim::SimulatorView now = sim.view();
    auto accepted = registers::validate_sim_write(table, start, values, config_.word_order, now.config,
                                                  switches_of(now), readback_of(now));
    if (!accepted) {
      refused = accepted.error();
      return;
    }
    const registers::AcceptedSimWrite& w = *accepted;
    // A carriage that moves (or is about to) keeps its geometry; faults,
    // noise, wiring and lost steps may strike it at any moment.
    for (const registers::Change& c : w.changes) {
      if (c.reg->per_axis() && registers::moves_geometry(c.reg->key) &&
          sim.in_motion(static_cast<std::size_t>(c.reg->axis), next)) {
        busy_reg = c.reg;
        return;
      }
    }
    for (std::size_t a = 0; a < homing::kAxisCount; ++a) {
      if (!w.axes_written[a]) continue;
      sim.set_axis_config(a, w.config.axes[a]);
      if (w.placed[a]) sim.place(a, w.config.axes[a].actual_position_mm);
      if (w.lose_steps_mm[a] != 0) sim.lose_steps(a, w.lose_steps_mm[a]);
    }
    if (w.seed_written) sim.set_seed(w.config.seed);
    sim.set_estop(w.switches.estop);
    sim.set_start_button(w.switches.start_button);
    changes = w.changes;
  };
  using registers::RefusalReason;
  if (!loop_.edit_sim(edit, std::chrono::seconds(2)))
    return refuse(fc,
                  registers::Refusal::because(RefusalReason::loop_not_responding, start,
                                              "the control loop did not take the simulator write in time"),
                  client);
  if (refused) return refuse(fc, *refused, client);
  if (busy_reg)
    return refuse(fc,
                  registers::Refusal::because(RefusalReason::carriage_moving, busy_reg->address,
                                              fmt::format("{} moves the carriage or what it meets: not written while "
                                                          "that carriage moves; write it when the axis rests",
                                                          busy_reg->name())),
                  client);
  if (!changes.empty())
    spdlog::info("simulator changed by {} {}: {}", client.transport, client.address,
                 describe_changes(changes, kinds));
  return std::nullopt;
}

}  // namespace server
