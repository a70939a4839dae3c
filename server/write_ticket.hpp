#pragma once
// ModbusService's write path, private to modbus_service_write.cpp (the batch)
// and modbus_service_writer.cpp (the settings writer): a write on its way
// through a batch, and a write taken to be answered later.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "modbus_service.hpp"
#include "request_decoder.hpp"

namespace server {

// One write of the module unit on its way through a batch.
struct ModbusService::WriteTicket {
  registers::Table table;
  std::uint16_t start = 0;
  std::span<const std::uint16_t> values;
  const ClientInfo& client;
  // Decided by the batch's leader, answered by the request's own thread.
  std::optional<registers::Refusal> refusal;
  std::vector<registers::CommandRequest> commands;
  bool done = false;  // under batch_mutex_, as lead
  bool lead = false;  // this request's thread decides and commits the next batch
  // Its own, so that a batch's end wakes exactly the threads it answers
  // (one wake-up shared by all had every waiting thread wake, take the lock
  // in turn and sleep again: some nine futex calls per write at 8 writers).
  std::condition_variable wake;
  LaterWrite* later = nullptr;  // taken by handle_later(): answered by the leader, nobody waits
};

// A write taken by handle_later(): it owns what its ticket refers to, and is
// answered through done by whichever thread led its batch.
struct ModbusService::LaterWrite {
  LaterWrite(FunctionCode function, WriteRequest request, ClientInfo who, std::function<void(Reply)> answer)
      : fc(function),
        write(std::move(request)),
        client(std::move(who)),
        done(std::move(answer)),
        ticket{write.table, write.start, write.values, client, std::nullopt, {}, false, false, {}, this} {}
  FunctionCode fc;
  WriteRequest write;
  ClientInfo client;
  std::function<void(Reply)> done;
  WriteTicket ticket;
};

}  // namespace server
