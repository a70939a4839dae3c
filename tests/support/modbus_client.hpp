#pragma once
// A libmodbus client that speaks the register table's names: reads and
// writes a named register on its unit (module or simulator) with the function
// code its table implies, 32-bit values in one request, high word first.
#include <modbus/modbus.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "registers/table.hpp"

namespace test_support {

// Modbus exception code of a failed libmodbus call's errno (0 if it was not an exception).
int exception_of(int err);

class Client {
 public:
  static Client tcp(int port, int module_unit = 1, int sim_unit = 247);
  static Client tcp(const std::string& host, int port, int module_unit, int sim_unit,
                    std::chrono::milliseconds timeout);
  static Client rtu(const std::string& device, int baud, char parity, int module_unit = 1);

  Client(Client&& o) noexcept;
  Client& operator=(Client&&) = delete;
  ~Client();

  modbus_t* ctx() const { return ctx_; }
  void close();
  void set_timeout(std::chrono::milliseconds t);
  void use_unit(int unit) { modbus_set_slave(ctx_, unit); }

  // Reads the raw value of a named register (FC 1/2/3/4 by its table); throws on failure.
  std::int64_t read(std::string_view name);
  // The same, nullopt on failure (last_errno() says why).
  std::optional<std::int64_t> try_read(std::string_view name);
  double read_mm(std::string_view name) { return static_cast<double>(read(name)) / 1000.0; }

  // Writes a raw value: coils FC 5, holding registers FC 16 (both words of a
  // 32-bit value in one request). Returns 0 or the Modbus exception code
  // (-1 for a transport error).
  int write(std::string_view name, std::int64_t raw);
  // Like write(), but a failure throws (for set-up steps).
  void set(std::string_view name, std::int64_t raw);

  // Plain block reads on the unit last used (the module unit at first, or the
  // unit set by use_unit()).
  std::optional<std::vector<std::uint16_t>> holding(int address, int count);
  std::optional<std::vector<std::uint16_t>> inputs(int address, int count);

  // Raw request (unit id + PDU) and its confirmation: the reply PDU with the
  // unit id first, as libmodbus returns it minus the framing; empty on error.
  std::vector<std::uint8_t> raw(const std::vector<std::uint8_t>& unit_and_pdu);

  int last_errno() const { return last_errno_; }
  int last_exception() const { return exception_of(last_errno_); }

 private:
  Client(modbus_t* ctx, int module_unit, int sim_unit, std::chrono::milliseconds timeout, const std::string& peer);
  void select(const registers::Register& r);
  std::optional<std::vector<std::uint16_t>> block(int (*read)(modbus_t*, int, int, std::uint16_t*), int address,
                                                  int count);

  modbus_t* ctx_ = nullptr;
  int module_unit_ = 1;
  int sim_unit_ = 247;
  int last_errno_ = 0;
};

// Every module holding register, name -> raw: "nothing changed" checks.
std::vector<std::pair<std::string, std::int64_t>> holding_snapshot(Client& c);

}  // namespace test_support
