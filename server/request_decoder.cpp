#include "request_decoder.hpp"

#include <modbus/modbus.h>

#include "pdu.hpp"

namespace server {
namespace {

using registers::ExceptionCode;
using registers::Table;
using Decoded = std::expected<Request, ExceptionCode>;

constexpr auto kBadValue = std::unexpected(ExceptionCode::illegal_data_value);

// FC 1-4: start, quantity.
Decoded decode_read(FunctionCode fc, std::span<const std::uint8_t> pdu) {
  if (pdu.size() != 5) return kBadValue;
  const std::uint16_t start = be16(pdu, 1), count = be16(pdu, 3);
  const bool bits = fc == FunctionCode::read_coils || fc == FunctionCode::read_discrete_inputs;
  if (count < 1 || count > (bits ? MODBUS_MAX_READ_BITS : MODBUS_MAX_READ_REGISTERS)) return kBadValue;
  Table table = Table::input_register;
  switch (fc) {
    case FunctionCode::read_coils: table = Table::coil; break;
    case FunctionCode::read_discrete_inputs: table = Table::discrete_input; break;
    case FunctionCode::read_holding_registers: table = Table::holding_register; break;
    default: break;
  }
  return Request{fc, ReadRequest{table, start, count}};
}

// FC 5: output value 0xFF00 (on) or 0x0000 (off), nothing else.
Decoded decode_write_coil(std::span<const std::uint8_t> pdu) {
  if (pdu.size() != 5) return kBadValue;
  const std::uint16_t value = be16(pdu, 3);
  if (value != 0xFF00 && value != 0x0000) return kBadValue;
  const std::uint16_t bit = value == 0xFF00 ? 1 : 0;
  return Request{FunctionCode::write_single_coil, WriteRequest{Table::coil, be16(pdu, 1), {bit}}};
}

Decoded decode_write_register(std::span<const std::uint8_t> pdu) {
  if (pdu.size() != 5) return kBadValue;
  return Request{FunctionCode::write_single_register,
                 WriteRequest{Table::holding_register, be16(pdu, 1), {be16(pdu, 3)}}};
}

// FC 15: start, quantity, byte count, bits packed LSB first.
Decoded decode_write_coils(std::span<const std::uint8_t> pdu) {
  if (pdu.size() < 6) return kBadValue;
  const std::uint16_t start = be16(pdu, 1), count = be16(pdu, 3);
  const std::uint8_t bytes = pdu[5];
  if (count < 1 || count > MODBUS_MAX_WRITE_BITS || bytes != (count + 7) / 8 || pdu.size() != 6u + bytes)
    return kBadValue;
  WriteRequest w{Table::coil, start, std::vector<std::uint16_t>(count)};
  for (std::uint16_t i = 0; i < count; ++i) w.values[i] = (pdu[6 + i / 8] >> (i % 8)) & 1;
  return Request{FunctionCode::write_multiple_coils, std::move(w)};
}

// `count` big-endian words from pdu[at].
std::vector<std::uint16_t> words_at(std::span<const std::uint8_t> pdu, std::size_t at, std::uint16_t count) {
  std::vector<std::uint16_t> words(count);
  for (std::uint16_t i = 0; i < count; ++i) words[i] = be16(pdu, at + 2u * i);
  return words;
}

// FC 16: start, quantity, byte count, words.
Decoded decode_write_registers(std::span<const std::uint8_t> pdu) {
  if (pdu.size() < 6) return kBadValue;
  const std::uint16_t start = be16(pdu, 1), count = be16(pdu, 3);
  const std::uint8_t bytes = pdu[5];
  if (count < 1 || count > MODBUS_MAX_WRITE_REGISTERS || bytes != count * 2 || pdu.size() != 6u + bytes)
    return kBadValue;
  return Request{FunctionCode::write_multiple_registers,
                 WriteRequest{Table::holding_register, start, words_at(pdu, 6, count)}};
}

// FC 23: read start, read quantity, write start, write quantity, byte count, words.
Decoded decode_read_write(std::span<const std::uint8_t> pdu) {
  if (pdu.size() < 10) return kBadValue;
  const std::uint16_t read_start = be16(pdu, 1), read_count = be16(pdu, 3);
  const std::uint16_t write_start = be16(pdu, 5), write_count = be16(pdu, 7);
  const std::uint8_t bytes = pdu[9];
  if (read_count < 1 || read_count > MODBUS_MAX_WR_READ_REGISTERS || write_count < 1 ||
      write_count > MODBUS_MAX_WR_WRITE_REGISTERS || bytes != write_count * 2 || pdu.size() != 10u + bytes)
    return kBadValue;
  return Request{FunctionCode::read_write_registers,
                 ReadWriteRequest{ReadRequest{Table::holding_register, read_start, read_count},
                                  WriteRequest{Table::holding_register, write_start, words_at(pdu, 10, write_count)}}};
}

// FC 20: byte count 0x07..0xF5, then sub-requests of 7 bytes each.
Decoded decode_file_record(std::span<const std::uint8_t> pdu) {
  if (pdu.size() < 2) return kBadValue;
  const std::uint8_t bytes = pdu[1];
  if (bytes < 7 || bytes > 0xF5 || bytes % 7 != 0 || pdu.size() != 2u + bytes) return kBadValue;
  FileRecordRequest r;
  for (std::size_t at = 2; at < pdu.size(); at += 7)
    r.records.push_back(FileRecordRef{pdu[at], be16(pdu, at + 1), be16(pdu, at + 3), be16(pdu, at + 5)});
  return Request{FunctionCode::read_file_record, std::move(r)};
}

// FC 43: MEI type 14 only (a MEI type the module lacks is an unknown function);
// read device ID code 1..4.
Decoded decode_encapsulated(std::span<const std::uint8_t> pdu) {
  constexpr std::uint8_t kReadDeviceId = 0x0E;
  if (pdu.size() != 4 || pdu[1] != kReadDeviceId) return std::unexpected(ExceptionCode::illegal_function);
  const std::uint8_t code = pdu[2];
  if (code < 1 || code > 4) return kBadValue;
  return Request{FunctionCode::encapsulated_interface, DeviceIdRequest{code, pdu[3]}};
}

// FC 8: sub-function, then data words. A sub-function the module does not
// implement is 01 (the specification's answer); data that does not fit it, 03.
Decoded decode_diagnostics(std::span<const std::uint8_t> pdu) {
  if (pdu.size() < 3 || (pdu.size() - 3) % 2 != 0) return kBadValue;
  DiagnosticsRequest r{be16(pdu, 1), words_at(pdu, 3, static_cast<std::uint16_t>((pdu.size() - 3) / 2))};
  using D = DiagnosticsRequest;
  const bool counter = r.sub_function >= D::clear_counters && r.sub_function <= D::last_counter;
  if (r.sub_function != D::return_query_data && r.sub_function != D::restart_communications && !counter)
    return std::unexpected(ExceptionCode::illegal_function);
  if (r.sub_function == D::restart_communications &&
      (r.data.size() != 1 || (r.data[0] != 0x0000 && r.data[0] != 0xFF00)))
    return kBadValue;
  if (counter && (r.data.size() != 1 || r.data[0] != 0)) return kBadValue;
  return Request{FunctionCode::diagnostics, std::move(r)};
}

// FC 17: the function code alone.
Decoded decode_report_server_id(std::span<const std::uint8_t> pdu) {
  if (pdu.size() != 1) return kBadValue;
  return Request{FunctionCode::report_server_id, ReportServerIdRequest{}};
}

}  // namespace

Decoded decode_request(std::span<const std::uint8_t> pdu) {
  const auto fc = static_cast<FunctionCode>(pdu[0]);
  switch (fc) {
    case FunctionCode::read_coils:
    case FunctionCode::read_discrete_inputs:
    case FunctionCode::read_holding_registers:
    case FunctionCode::read_input_registers: return decode_read(fc, pdu);
    case FunctionCode::write_single_coil: return decode_write_coil(pdu);
    case FunctionCode::write_single_register: return decode_write_register(pdu);
    case FunctionCode::write_multiple_coils: return decode_write_coils(pdu);
    case FunctionCode::write_multiple_registers: return decode_write_registers(pdu);
    case FunctionCode::read_file_record: return decode_file_record(pdu);
    case FunctionCode::read_write_registers: return decode_read_write(pdu);
    case FunctionCode::encapsulated_interface: return decode_encapsulated(pdu);
    case FunctionCode::diagnostics: return decode_diagnostics(pdu);
    case FunctionCode::report_server_id: return decode_report_server_id(pdu);
  }
  return std::unexpected(ExceptionCode::illegal_function);
}

}  // namespace server
