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

// A simulator write between its decision inside the control loop and its answer.
struct ModbusService::SimWrite {
  std::uint8_t fc = 0;
  registers::Table table{};
  std::uint16_t start = 0;
  std::vector<std::uint16_t> values;
  ClientInfo client;
  registers::AxisKinds kinds{};
  // Decided inside the loop:
  std::optional<registers::Refusal> refused{};
  const registers::Register* busy_reg = nullptr;
  std::vector<registers::Change> changes{};
};

// The rest of a write whose address, access and range passed: decided and
// applied on the live simulator inside the control loop (never on a snapshot
// that may miss the previous write), and answered once a snapshot shows it:
// an acknowledged write holds and reads back.
ControlLoop::SimEdit ModbusService::sim_edit(std::shared_ptr<SimWrite> write) const {
  return [write = std::move(write), word_order = config_.word_order](homing::sim::SimulatorControls& sim,
                                                                     const homing::Outputs& next) {
    SimWrite& ws = *write;
    const homing::sim::SimulatorView now = sim.view();
    auto accepted = registers::validate_sim_write(ws.table, ws.start, ws.values, word_order, now.config,
                                                  switches_of(now), readback_of(now));
    if (!accepted) {
      ws.refused = accepted.error();
      return;
    }
    const registers::AcceptedSimWrite& w = *accepted;
    // A carriage that moves (or is about to) keeps its geometry; faults,
    // noise, wiring and lost steps may strike it at any moment.
    for (const registers::Change& c : w.changes) {
      if (c.reg->per_axis() && registers::moves_geometry(c.reg->key) &&
          sim.in_motion(static_cast<std::size_t>(c.reg->axis), next)) {
        ws.busy_reg = c.reg;
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
    ws.changes = w.changes;
  };
}

// Its refusal or its log line once the loop has shown (or not taken) it;
// nullopt when accepted.
std::optional<Reply> ModbusService::sim_outcome(const SimWrite& w, bool shown) {
  using registers::RefusalReason;
  if (!shown)
    return refuse(w.fc,
                  registers::Refusal::because(RefusalReason::loop_not_responding, w.start,
                                              "the control loop did not take the simulator write in time"),
                  w.client);
  if (w.refused) return refuse(w.fc, *w.refused, w.client);
  if (w.busy_reg)
    return refuse(w.fc,
                  registers::Refusal::because(RefusalReason::carriage_moving, w.busy_reg->address,
                                              fmt::format("{} moves the carriage or what it meets: not written while "
                                                          "that carriage moves; write it when the axis rests",
                                                          w.busy_reg->name())),
                  w.client);
  if (!w.changes.empty())
    spdlog::info("simulator changed by {} {}: {}", w.client.transport, w.client.address,
                 describe_changes(w.changes, w.kinds));
  return std::nullopt;
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
  auto write = std::make_shared<SimWrite>(
      SimWrite{fc, table, start, std::vector<std::uint16_t>(values.begin(), values.end()), client, kinds});
  const bool shown = loop_.edit_sim(sim_edit(write), std::chrono::seconds(2));
  return sim_outcome(*write, shown);
}

// A write of the simulator unit on an event loop: checked at once like
// handle(), then handed to the control loop, which answers it once a
// published period shows it; no thread waits for it meanwhile. Its refusal
// or log line is made on the event loop's thread (Reply::resolve), never on
// the control loop's.
bool ModbusService::write_sim_later(std::span<const std::uint8_t> pdu, const ClientInfo& client,
                                    std::function<void(Reply)> done) {
  auto request = decode_request(pdu);
  if (!request) return false;  // answered by handle() with its exception
  auto* w = std::get_if<WriteRequest>(&request->body);
  if (!w) return false;
  const auto function = request->function;
  const auto fc = static_cast<std::uint8_t>(function);
  diagnostics_.addressed(client.transport);
  const auto answer_now = [&](Reply reply) {
    diagnostics_.answered(client.transport, reply);
    done(std::move(reply));
  };
  const registers::AxisKinds kinds = registers::kinds_of(settings());
  {
    written_start_ = w->start;  // what the client wrote, beside what a refusal is about
    std::optional<Reply> refused;
    if (auto r = client_refusal(registers::Unit::simulator, w->table, w->start, w->values.size(), client,
                                may_write(client)))
      refused = refuse(fc, *r, client);
    else if (auto decoded = registers::decode_write(registers::Unit::simulator, w->table, w->start, w->values,
                                                    config_.word_order, kinds);
             !decoded)
      refused = refuse(fc, decoded.error(), client);
    written_start_.reset();
    if (refused) {
      answer_now(std::move(*refused));
      return true;
    }
  }
  auto write = std::make_shared<SimWrite>(SimWrite{fc, w->table, w->start, w->values, client, kinds});
  loop_.edit_sim_later(sim_edit(write), [this, write, function, done = std::move(done)](bool shown) {
    Reply deferred;
    deferred.resolve = [this, write, function, shown] {
      written_start_ = write->start;
      std::optional<Reply> refused = sim_outcome(*write, shown);
      written_start_.reset();
      Reply reply = refused ? std::move(*refused)
                            : accepted_write_reply(function, WriteRequest{write->table, write->start, write->values});
      diagnostics_.answered(write->client.transport, reply);
      return reply;
    };
    done(std::move(deferred));
  });
  return true;
}

}  // namespace server
