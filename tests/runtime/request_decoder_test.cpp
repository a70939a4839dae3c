// The request decoder alone (server/request_decoder.hpp): what a well-formed
// request asks for, and the exception the Modbus application protocol requires
// of a malformed one, at libmodbus's MODBUS_MAX_* limits and one past them.
#include <catch2/catch.hpp>

#include <modbus/modbus.h>

#include <cstdint>
#include <optional>
#include <variant>
#include <vector>

#include "server/request_decoder.hpp"

namespace {

using registers::ExceptionCode;
using registers::Table;
using server::decode_request;
using server::FunctionCode;
using Bytes = std::vector<std::uint8_t>;

void put16(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
}

// fc, a, b: the shape of FC 1-6 requests.
Bytes pdu(std::uint8_t fc, std::uint16_t a, std::uint16_t b) {
  Bytes r{fc};
  put16(r, a);
  put16(r, b);
  return r;
}

// FC 16 with `quantity` in its header, `byte_count` as given and `words` words of data.
Bytes write_registers(std::uint16_t start, std::uint16_t quantity, std::uint8_t byte_count, std::size_t words) {
  Bytes r = pdu(16, start, quantity);
  r.push_back(byte_count);
  for (std::size_t i = 0; i < words; ++i) put16(r, static_cast<std::uint16_t>(0x0100 + i));
  return r;
}

// FC 15 with `quantity` coils, `byte_count` as given and `bytes` bytes of data.
Bytes write_coils(std::uint16_t start, std::uint16_t quantity, std::uint8_t byte_count, std::size_t bytes) {
  Bytes r = pdu(15, start, quantity);
  r.push_back(byte_count);
  r.insert(r.end(), bytes, 0x00);
  return r;
}

// FC 23: read quantity, write quantity, byte count, `words` words of data.
Bytes read_write(std::uint16_t read_count, std::uint16_t write_count, std::uint8_t byte_count, std::size_t words) {
  Bytes r = pdu(23, 100, read_count);
  put16(r, 200);
  put16(r, write_count);
  r.push_back(byte_count);
  for (std::size_t i = 0; i < words; ++i) put16(r, 7);
  return r;
}

// The exception a request is refused with, or nullopt when it decodes.
std::optional<ExceptionCode> refusal(const Bytes& request) {
  const auto decoded = decode_request(request);
  if (decoded) return std::nullopt;
  return decoded.error();
}

template <class Body>
Body body_of(const Bytes& request) {
  const auto decoded = decode_request(request);
  REQUIRE(decoded);
  REQUIRE(std::holds_alternative<Body>(decoded->body));
  return std::get<Body>(decoded->body);
}

}  // namespace

TEST_CASE("decoder: a read of MODBUS_MAX_READ_REGISTERS registers decodes, one more is exception 03") {
  for (std::uint8_t fc : {3, 4}) {
    INFO("FC " << int(fc));
    const auto read = body_of<server::ReadRequest>(pdu(fc, 100, MODBUS_MAX_READ_REGISTERS));
    CHECK(read.table == (fc == 3 ? Table::holding_register : Table::input_register));
    CHECK(read.start == 100);
    CHECK(read.count == MODBUS_MAX_READ_REGISTERS);
    CHECK(refusal(pdu(fc, 100, MODBUS_MAX_READ_REGISTERS + 1)) == ExceptionCode::illegal_data_value);
  }
}

TEST_CASE("decoder: a read of MODBUS_MAX_READ_BITS coils or discrete inputs decodes, one more is exception 03") {
  for (std::uint8_t fc : {1, 2}) {
    INFO("FC " << int(fc));
    const auto read = body_of<server::ReadRequest>(pdu(fc, 0, MODBUS_MAX_READ_BITS));
    CHECK(read.table == (fc == 1 ? Table::coil : Table::discrete_input));
    CHECK(read.count == MODBUS_MAX_READ_BITS);
    CHECK(refusal(pdu(fc, 0, MODBUS_MAX_READ_BITS + 1)) == ExceptionCode::illegal_data_value);
  }
}

TEST_CASE("decoder: a read or write of zero items is exception 03") {
  for (std::uint8_t fc : {1, 2, 3, 4}) {
    INFO("FC " << int(fc));
    CHECK(refusal(pdu(fc, 0, 0)) == ExceptionCode::illegal_data_value);
  }
  CHECK(refusal(write_registers(100, 0, 0, 0)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(write_coils(0, 0, 0, 0)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(read_write(0, 1, 2, 1)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(read_write(1, 0, 0, 0)) == ExceptionCode::illegal_data_value);
}

TEST_CASE("decoder: a write of MODBUS_MAX_WRITE_REGISTERS registers decodes, one more is exception 03") {
  const auto write = body_of<server::WriteRequest>(
      write_registers(100, MODBUS_MAX_WRITE_REGISTERS, 2 * MODBUS_MAX_WRITE_REGISTERS, MODBUS_MAX_WRITE_REGISTERS));
  CHECK(write.table == Table::holding_register);
  CHECK(write.start == 100);
  REQUIRE(write.values.size() == MODBUS_MAX_WRITE_REGISTERS);
  CHECK(write.values.front() == 0x0100);
  CHECK(write.values.back() == 0x0100 + MODBUS_MAX_WRITE_REGISTERS - 1);
  // 124 registers do not fit a PDU: the quantity says 124 with as much data as fits.
  CHECK(refusal(write_registers(100, MODBUS_MAX_WRITE_REGISTERS + 1, 248, MODBUS_MAX_WRITE_REGISTERS)) ==
        ExceptionCode::illegal_data_value);
}

TEST_CASE("decoder: a write-multiple-registers whose byte count disagrees with its quantity is exception 03") {
  CHECK(refusal(write_registers(100, 2, 3, 2)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(write_registers(100, 2, 2, 1)) == ExceptionCode::illegal_data_value);
  // The byte count is right but the data that follows is not that long.
  CHECK(refusal(write_registers(100, 2, 4, 1)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(write_registers(100, 2, 4, 3)) == ExceptionCode::illegal_data_value);
  CHECK(body_of<server::WriteRequest>(write_registers(100, 2, 4, 2)).values == std::vector<std::uint16_t>{0x0100, 0x0101});
}

TEST_CASE("decoder: a write of MODBUS_MAX_WRITE_BITS coils decodes, one more is exception 03") {
  const std::uint8_t bytes = (MODBUS_MAX_WRITE_BITS + 7) / 8;
  CHECK(body_of<server::WriteRequest>(write_coils(0, MODBUS_MAX_WRITE_BITS, bytes, bytes)).values.size() ==
        MODBUS_MAX_WRITE_BITS);
  CHECK(refusal(write_coils(0, MODBUS_MAX_WRITE_BITS + 1, bytes + 1, bytes + 1)) == ExceptionCode::illegal_data_value);
}

TEST_CASE("decoder: a write-multiple-coils whose byte count disagrees with its quantity is exception 03") {
  CHECK(refusal(write_coils(0, 9, 1, 1)) == ExceptionCode::illegal_data_value);  // 9 coils need 2 bytes
  CHECK(refusal(write_coils(0, 8, 2, 2)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(write_coils(0, 9, 2, 1)) == ExceptionCode::illegal_data_value);
}

TEST_CASE("decoder: coils written with FC 15 are unpacked least significant bit first") {
  Bytes request = write_coils(16, 10, 2, 0);
  request.push_back(0b1000'0101);  // coils 16, 18, 23
  request.push_back(0b0000'0010);  // coil 25
  const auto write = body_of<server::WriteRequest>(request);
  CHECK(write.table == Table::coil);
  CHECK(write.start == 16);
  CHECK(write.values == std::vector<std::uint16_t>{1, 0, 1, 0, 0, 0, 0, 1, 0, 1});
}

TEST_CASE("decoder: a single-coil write of FF00 is on, 0000 off, any other value is exception 03") {
  const auto on = body_of<server::WriteRequest>(pdu(5, 7, 0xFF00));
  CHECK(on.table == Table::coil);
  CHECK(on.start == 7);
  CHECK(on.values == std::vector<std::uint16_t>{1});
  CHECK(body_of<server::WriteRequest>(pdu(5, 7, 0x0000)).values == std::vector<std::uint16_t>{0});
  for (std::uint16_t value : {0x0001, 0x00FF, 0xFF01, 0xFFFF, 0x0100}) {
    INFO("value " << value);
    CHECK(refusal(pdu(5, 7, value)) == ExceptionCode::illegal_data_value);
  }
}

TEST_CASE("decoder: a single-register write carries its address and value") {
  const auto write = body_of<server::WriteRequest>(pdu(6, 0x1234, 0xBEEF));
  CHECK(write.table == Table::holding_register);
  CHECK(write.start == 0x1234);
  CHECK(write.values == std::vector<std::uint16_t>{0xBEEF});
}

TEST_CASE("decoder: a request longer or shorter than its function's fields is exception 03") {
  for (std::uint8_t fc : {1, 2, 3, 4, 5, 6}) {
    INFO("FC " << int(fc));
    Bytes longer = pdu(fc, 0, fc == 5 ? 0xFF00 : 1);
    longer.push_back(0);
    CHECK(refusal(longer) == ExceptionCode::illegal_data_value);
    CHECK(refusal(Bytes{fc, 0, 0, 0}) == ExceptionCode::illegal_data_value);
    CHECK(refusal(Bytes{fc}) == ExceptionCode::illegal_data_value);
  }
  for (std::uint8_t fc : {15, 16, 23, 20}) {
    INFO("FC " << int(fc));
    CHECK(refusal(Bytes{fc}) == ExceptionCode::illegal_data_value);
  }
}

TEST_CASE("decoder: an unknown function code is exception 01") {
  // 7 (read exception status), 11 (get comm event counter), 12, 0x41
  // (user-defined), 0 and codes with the exception bit set.
  for (std::uint8_t fc : {0, 7, 11, 12, 21, 22, 24, 0x41, 0x64, 0x83, 0xFF}) {
    INFO("FC " << int(fc));
    CHECK(refusal(Bytes{fc, 0, 0, 0, 1}) == ExceptionCode::illegal_function);
  }
}

TEST_CASE("decoder: read/write registers decodes at MODBUS_MAX_WR_* and is exception 03 one past either") {
  const auto rw = body_of<server::ReadWriteRequest>(
      read_write(MODBUS_MAX_WR_READ_REGISTERS, MODBUS_MAX_WR_WRITE_REGISTERS, 2 * MODBUS_MAX_WR_WRITE_REGISTERS,
                 MODBUS_MAX_WR_WRITE_REGISTERS));
  CHECK(rw.read.table == Table::holding_register);
  CHECK(rw.read.start == 100);
  CHECK(rw.read.count == MODBUS_MAX_WR_READ_REGISTERS);
  CHECK(rw.write.start == 200);
  CHECK(rw.write.values.size() == MODBUS_MAX_WR_WRITE_REGISTERS);
  CHECK(refusal(read_write(MODBUS_MAX_WR_READ_REGISTERS + 1, 1, 2, 1)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(read_write(1, MODBUS_MAX_WR_WRITE_REGISTERS + 1, 2 * (MODBUS_MAX_WR_WRITE_REGISTERS + 1),
                           MODBUS_MAX_WR_WRITE_REGISTERS)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(read_write(1, 2, 3, 2)) == ExceptionCode::illegal_data_value);  // byte count disagrees
}

TEST_CASE("decoder: device identification needs MEI type 14 (else 01) and a read code 1 to 4 (else 03)") {
  const auto id = body_of<server::DeviceIdRequest>(Bytes{43, 0x0E, 4, 3});
  CHECK(id.read_code == 4);
  CHECK(id.object_id == 3);
  CHECK(refusal(Bytes{43, 0x0D, 1, 0}) == ExceptionCode::illegal_function);  // CANopen general reference
  CHECK(refusal(Bytes{43, 0x0E, 1}) == ExceptionCode::illegal_function);
  CHECK(refusal(Bytes{43, 0x0E, 0, 0}) == ExceptionCode::illegal_data_value);
  CHECK(refusal(Bytes{43, 0x0E, 5, 0}) == ExceptionCode::illegal_data_value);
}

TEST_CASE("decoder: a file record request is whole 7-byte sub-requests, else exception 03") {
  const Bytes two{20, 14, 6, 0, 1, 0, 0, 0, 10, 6, 0, 3, 0, 20, 0, 4};
  const auto files = body_of<server::FileRecordRequest>(two);
  REQUIRE(files.records.size() == 2);
  CHECK(files.records[0].reference_type == 6);
  CHECK(files.records[0].file == 1);
  CHECK(files.records[0].record == 0);
  CHECK(files.records[0].length == 10);
  CHECK(files.records[1].file == 3);
  CHECK(files.records[1].record == 20);
  CHECK(files.records[1].length == 4);
  CHECK(refusal(Bytes{20, 6, 6, 0, 1, 0, 0, 0}) == ExceptionCode::illegal_data_value);        // not 7 bytes
  CHECK(refusal(Bytes{20, 7, 6, 0, 1, 0, 0, 0}) == ExceptionCode::illegal_data_value);        // 7 announced, 6 sent
  CHECK(refusal(Bytes{20, 7, 6, 0, 1, 0, 0, 0, 1, 0}) == ExceptionCode::illegal_data_value);  // one byte too many
}

TEST_CASE("decoder: diagnostics serve sub-functions 00, 01 and 0A to 12, any other is exception 01") {
  for (std::uint16_t sub : {0x00, 0x01, 0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F, 0x10, 0x11, 0x12}) {
    INFO("sub-function " << sub);
    const auto d = body_of<server::DiagnosticsRequest>(pdu(8, sub, 0));
    CHECK(d.sub_function == sub);
    CHECK(d.data == std::vector<std::uint16_t>{0});
  }
  for (std::uint16_t sub : {0x02, 0x03, 0x04, 0x09, 0x13, 0x14, 0x15, 0xFFFF}) {
    INFO("sub-function " << sub);
    CHECK(refusal(pdu(8, sub, 0)) == ExceptionCode::illegal_function);
  }
}

TEST_CASE("decoder: diagnostics data must fit the sub-function, else exception 03") {
  // 00 echoes any number of words.
  Bytes echo{8, 0, 0};
  for (std::uint16_t w : {0x1234, 0xABCD, 0x0000}) put16(echo, w);
  CHECK(body_of<server::DiagnosticsRequest>(echo).data == std::vector<std::uint16_t>{0x1234, 0xABCD, 0x0000});
  CHECK(refusal(Bytes{8, 0, 0, 0x12}) == ExceptionCode::illegal_data_value);  // half a word
  CHECK(refusal(Bytes{8, 0}) == ExceptionCode::illegal_data_value);          // no sub-function
  // 01: 0000 or FF00 only.
  CHECK(body_of<server::DiagnosticsRequest>(pdu(8, 0x01, 0xFF00)).data == std::vector<std::uint16_t>{0xFF00});
  CHECK(refusal(pdu(8, 0x01, 0x1234)) == ExceptionCode::illegal_data_value);
  // The counters: 0000 only, one word.
  CHECK(refusal(pdu(8, 0x0B, 0x0001)) == ExceptionCode::illegal_data_value);
  CHECK(refusal(Bytes{8, 0, 0x0B}) == ExceptionCode::illegal_data_value);
  Bytes two = pdu(8, 0x0E, 0);
  put16(two, 0);
  CHECK(refusal(two) == ExceptionCode::illegal_data_value);
}

TEST_CASE("decoder: report server id is the function code alone, anything after it is exception 03") {
  const auto decoded = decode_request(Bytes{17});
  REQUIRE(decoded);
  CHECK(decoded->function == FunctionCode::report_server_id);
  CHECK(refusal(Bytes{17, 0}) == ExceptionCode::illegal_data_value);
}
