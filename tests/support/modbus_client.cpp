#include "tests/support/modbus_client.hpp"

#include <cerrno>
#include <span>
#include <stdexcept>

#include "registers/codec.hpp"
#include "registers/lookup.hpp"
#include "tests/support/named_registers.hpp"

namespace test_support {

using namespace std::chrono_literals;

int exception_of(int err) {
  if (err > MODBUS_ENOBASE && err <= EMBXGTAR) return err - MODBUS_ENOBASE;
  return 0;
}

Client Client::tcp(int port, int module_unit, int sim_unit) { return tcp("127.0.0.1", port, module_unit, sim_unit, 1000ms); }

Client Client::tcp(const std::string& host, int port, int module_unit, int sim_unit, std::chrono::milliseconds timeout) {
  modbus_t* ctx = modbus_new_tcp(host.c_str(), port);
  if (!ctx) throw std::runtime_error("modbus_new_tcp failed");
  return Client(ctx, module_unit, sim_unit, timeout, host + ":" + std::to_string(port));
}

Client Client::rtu(const std::string& device, int baud, char parity, int module_unit) {
  modbus_t* ctx = modbus_new_rtu(device.c_str(), baud, parity, 8, 1);
  if (!ctx) throw std::runtime_error("modbus_new_rtu failed");
  return Client(ctx, module_unit, -1, 1000ms, device);
}

Client::Client(modbus_t* ctx, int module_unit, int sim_unit, std::chrono::milliseconds timeout,
               const std::string& peer)
    : ctx_(ctx), module_unit_(module_unit), sim_unit_(sim_unit) {
  set_timeout(timeout);
  if (modbus_connect(ctx_) != 0) {
    const int e = errno;
    modbus_free(ctx_);
    ctx_ = nullptr;
    throw std::runtime_error("cannot connect to " + peer + ": " + modbus_strerror(e));
  }
  modbus_set_slave(ctx_, module_unit_);
}

Client::Client(Client&& o) noexcept
    : ctx_(o.ctx_), module_unit_(o.module_unit_), sim_unit_(o.sim_unit_), last_errno_(o.last_errno_) {
  o.ctx_ = nullptr;
}

Client::~Client() { close(); }

void Client::close() {
  if (ctx_) {
    modbus_close(ctx_);
    modbus_free(ctx_);
    ctx_ = nullptr;
  }
}

void Client::set_timeout(std::chrono::milliseconds t) {
  modbus_set_response_timeout(ctx_, static_cast<std::uint32_t>(t.count() / 1000),
                              static_cast<std::uint32_t>((t.count() % 1000) * 1000));
}

void Client::select(const registers::Register& r) {
  const int unit = r.unit == registers::Unit::simulator ? sim_unit_ : module_unit_;
  if (unit < 0) throw std::runtime_error("this client has no simulator unit (RTU): " + std::string(r.name()));
  modbus_set_slave(ctx_, unit);
}

std::int64_t Client::read(std::string_view name) {
  auto v = try_read(name);
  if (!v) throw std::runtime_error("read " + std::string(name) + ": " + modbus_strerror(last_errno_));
  return *v;
}

std::optional<std::int64_t> Client::try_read(std::string_view name) {
  const registers::Register& r = reg(name);
  select(r);
  int rc = -1;
  std::uint16_t words[2] = {0, 0};
  std::uint8_t bit = 0;
  switch (r.table) {
    case registers::Table::coil: rc = modbus_read_bits(ctx_, r.address, 1, &bit); break;
    case registers::Table::discrete_input: rc = modbus_read_input_bits(ctx_, r.address, 1, &bit); break;
    case registers::Table::holding_register: rc = modbus_read_registers(ctx_, r.address, r.words(), words); break;
    case registers::Table::input_register: rc = modbus_read_input_registers(ctx_, r.address, r.words(), words); break;
  }
  if (rc < 0) {
    last_errno_ = errno;
    return std::nullopt;
  }
  if (r.table == registers::Table::coil || r.table == registers::Table::discrete_input) return bit;
  return registers::decode_words(r, std::span<const std::uint16_t>(words, r.words()), registers::WordOrder::high_first);
}

int Client::write(std::string_view name, std::int64_t raw) {
  const registers::Register& r = reg(name);
  select(r);
  int rc = -1;
  if (r.table == registers::Table::coil) {
    rc = modbus_write_bit(ctx_, r.address, raw != 0 ? 1 : 0);
  } else {
    std::uint16_t words[2] = {0, 0};
    registers::encode_words(r, raw, registers::WordOrder::high_first, std::span<std::uint16_t>(words, r.words()));
    rc = modbus_write_registers(ctx_, r.address, r.words(), words);
  }
  if (rc >= 0) return 0;
  last_errno_ = errno;
  const int ex = exception_of(last_errno_);
  return ex ? ex : -1;
}

void Client::set(std::string_view name, std::int64_t raw) {
  const int rc = write(name, raw);
  if (rc != 0)
    throw std::runtime_error("write " + std::string(name) + " = " + std::to_string(raw) + " failed: " +
                             (rc > 0 ? "exception " + std::to_string(rc) : modbus_strerror(last_errno_)));
}

std::optional<std::vector<std::uint16_t>> Client::holding(int address, int count) {
  return block(modbus_read_registers, address, count);
}

std::optional<std::vector<std::uint16_t>> Client::inputs(int address, int count) {
  return block(modbus_read_input_registers, address, count);
}

std::optional<std::vector<std::uint16_t>> Client::block(int (*read)(modbus_t*, int, int, std::uint16_t*), int address,
                                                        int count) {
  std::vector<std::uint16_t> w(static_cast<std::size_t>(count));
  if (read(ctx_, address, count, w.data()) < 0) {
    last_errno_ = errno;
    return std::nullopt;
  }
  return w;
}

std::vector<std::uint8_t> Client::raw(const std::vector<std::uint8_t>& unit_and_pdu) {
  if (modbus_send_raw_request(ctx_, unit_and_pdu.data(), static_cast<int>(unit_and_pdu.size())) < 0) {
    last_errno_ = errno;
    return {};
  }
  std::uint8_t rsp[MODBUS_MAX_ADU_LENGTH];
  const int n = modbus_receive_confirmation(ctx_, rsp);
  if (n < 0) {
    last_errno_ = errno;
    return {};
  }
  const int header = modbus_get_header_length(ctx_);  // TCP: 7 (MBAP incl. unit), RTU: 1 (unit)
  // Keep the unit id, drop the rest of the header (and the RTU CRC).
  const bool rtu = header == 1;
  return std::vector<std::uint8_t>(rsp + header - 1, rsp + n - (rtu ? 2 : 0));
}

std::vector<std::pair<std::string, std::int64_t>> holding_snapshot(Client& c) {
  std::vector<std::pair<std::string, std::int64_t>> out;
  for (const registers::Register& r : registers::registers_of(registers::Unit::module))
    if (r.table == registers::Table::holding_register) out.emplace_back(r.name(), c.read(r.name()));
  return out;
}

}  // namespace test_support
