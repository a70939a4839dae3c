// ModbusService: the settings writer. Writes to the module unit that arrive
// on an event loop (TCP, TLS) are taken here instead of running on a thread
// of their own that waits for its batch: one thread leads every batch whose
// first write was taken, and whichever thread leads a batch answers the
// taken writes in it through their loops. A settings write then costs a
// hand-over to the writer and one back, shared by every write of its batch,
// where a thread per write was woken, waited and was woken again.
#include <spdlog/spdlog.h>

#include "modbus_service.hpp"
#include "thread_name.hpp"
#include "write_ticket.hpp"

namespace server {

bool ModbusService::handle_later(std::uint8_t unit, std::span<const std::uint8_t> pdu, const ClientInfo& client,
                                 std::function<void(Reply)> done) {
  if (pdu.empty() || !over_network(client.transport)) return false;
  if (!module_unit(unit, true)) {
    if (config_.sim_unit_id && unit == *config_.sim_unit_id) return write_sim_later(pdu, client, std::move(done));
    return false;
  }
  const auto function = static_cast<FunctionCode>(pdu[0]);
  if (function != FunctionCode::write_single_coil && function != FunctionCode::write_single_register &&
      function != FunctionCode::write_multiple_coils && function != FunctionCode::write_multiple_registers)
    return false;
  auto request = decode_request(pdu);
  if (!request) return false;  // answered by handle() with its exception
  auto* w = std::get_if<WriteRequest>(&request->body);
  if (!w) return false;
  diagnostics_.addressed(client.transport);
  auto* later = new LaterWrite(function, std::move(*w), client, std::move(done));  // owned by answer_later()
  bool wake = false;
  {
    std::lock_guard lock(batch_mutex_);
    if (!writer_.joinable()) writer_ = std::thread([this] { run_writer(); });
    batch_queue_.push_back(&later->ticket);
    if (!batch_leader_) batch_leader_ = writer_leads_ = wake = true;
  }
  if (wake) writer_wake_.notify_one();
  return true;
}

void ModbusService::run_writer() {
  name_this_thread("settings-write");
  std::unique_lock lock(batch_mutex_);
  for (;;) {
    writer_wake_.wait(lock, [this] { return writer_leads_ || writer_stops_; });
    // Stopping: the listeners are gone, and they wait for their writes'
    // answers before they go, so nothing is queued for the writer.
    if (!writer_leads_) return;
    writer_leads_ = false;
    lead(lock, nullptr);
  }
}

// Not under any lock: the same answer handle() gives, through the loop.
void ModbusService::answer_later(LaterWrite& w) {
  const std::unique_ptr<LaterWrite> owned(&w);
  const auto fc = static_cast<std::uint8_t>(w.fc);
  Reply reply;
  if (w.ticket.refusal) {
    written_start_ = w.write.start;  // what the client wrote, beside what the refusal is about
    reply = refuse(fc, *w.ticket.refusal, w.client);
    written_start_.reset();
  } else {
    run_commands(w.ticket.commands, w.client);
    reply = accepted_write_reply(w.fc, w.write);
  }
  diagnostics_.answered(w.client.transport, reply);
  w.done(std::move(reply));
}

}  // namespace server
