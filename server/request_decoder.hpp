#pragma once
// The Modbus request decoder: what a request PDU asks for (function code,
// addresses, quantities, values), or the exception the Modbus application
// protocol specification requires of a malformed one: 01 for a function code
// the module does not implement, 03 for a length that does not fit the
// function, a quantity outside libmodbus's MODBUS_MAX_* limits or a byte count
// that disagrees with its quantity. Pure: no register table, no state, no
// client. Whether the addresses exist and whether the request may be applied
// is decided by whoever applies it (ModbusService).
#include <cstdint>
#include <expected>
#include <span>
#include <variant>
#include <vector>

#include "registers/errors.hpp"
#include "registers/table.hpp"

namespace server {

// The function codes the module implements.
enum class FunctionCode : std::uint8_t {
  read_coils = 1,
  read_discrete_inputs = 2,
  read_holding_registers = 3,
  read_input_registers = 4,
  write_single_coil = 5,
  write_single_register = 6,
  diagnostics = 8,  // serial line diagnostics: sub-functions 00, 01, 0A..12
  write_multiple_coils = 15,
  write_multiple_registers = 16,
  report_server_id = 17,
  read_file_record = 20,
  read_write_registers = 23,
  encapsulated_interface = 43,  // only MEI type 14, read device identification
};

// FC 1-4: `count` bits or registers of `table` from `start`.
struct ReadRequest {
  registers::Table table = registers::Table::holding_register;
  std::uint16_t start = 0;
  std::uint16_t count = 0;
};

// FC 5, 6, 15, 16: one word per register, or one 0/1 per coil.
struct WriteRequest {
  registers::Table table = registers::Table::holding_register;
  std::uint16_t start = 0;
  std::vector<std::uint16_t> values;
};

// FC 23: holding registers; the write is applied before the read.
struct ReadWriteRequest {
  ReadRequest read;
  WriteRequest write;
};

// FC 20: one sub-request, as sent (whether the file and records exist is the
// file's owner's question: server/trace.hpp).
struct FileRecordRef {
  std::uint8_t reference_type = 0;
  std::uint16_t file = 0;
  std::uint16_t record = 0;
  std::uint16_t length = 0;  // registers
};
struct FileRecordRequest {
  std::vector<FileRecordRef> records;
};

// FC 43 / MEI 14: read device ID code 1 (basic stream), 2 (regular stream),
// 3 (extended stream) or 4 (one object), from object_id.
struct DeviceIdRequest {
  std::uint8_t read_code = 1;
  std::uint8_t object_id = 0;
};

// FC 8: a sub-function the module implements and its data: any number of
// words for 00 (echoed), 0000 or FF00 for 01, 0000 for 0A..12.
struct DiagnosticsRequest {
  static constexpr std::uint16_t return_query_data = 0x00;
  static constexpr std::uint16_t restart_communications = 0x01;
  static constexpr std::uint16_t clear_counters = 0x0A;
  static constexpr std::uint16_t last_counter = 0x12;  // 0B..12: the counters
  std::uint16_t sub_function = 0;
  std::vector<std::uint16_t> data;
};

// FC 17: no fields.
struct ReportServerIdRequest {};

struct Request {
  FunctionCode function = FunctionCode::read_holding_registers;
  std::variant<ReadRequest, WriteRequest, ReadWriteRequest, FileRecordRequest, DeviceIdRequest, DiagnosticsRequest,
               ReportServerIdRequest>
      body;
};

// The PDU must not be empty (pdu[0] is the function code).
std::expected<Request, registers::ExceptionCode> decode_request(std::span<const std::uint8_t> pdu);

// Function codes that change something when applied (a broadcast is applied
// only for these).
constexpr bool is_write(FunctionCode fc) {
  return fc == FunctionCode::write_single_coil || fc == FunctionCode::write_single_register ||
         fc == FunctionCode::write_multiple_coils || fc == FunctionCode::write_multiple_registers ||
         fc == FunctionCode::read_write_registers;
}

}  // namespace server
