#pragma once
// A Modbus client connection (libmodbus: TCP, RTU, or TCP inside TLS through
// a TlsTunnel) that knows the register
// table: reads and writes by register, grouped into few requests (a slow RTU
// line matters), FC 20 file records framed by hand (libmodbus has no client
// call for them and cannot size their response).
#include <modbus/modbus.h>

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "registers/codec.hpp"
#include "registers/table.hpp"

namespace homingctl {

class TlsTunnel;

struct ConnectionOptions {
  std::string tcp = "127.0.0.1:1502";  // HOST:PORT
  std::string rtu;                     // serial device; wins over tcp when set
  std::string tls;                     // Modbus/TCP Security HOST[:PORT]; wins over tcp when set
  std::string cert, key, ca;           // for tls: this client's certificate and key, the module's CA
  int baud = 19200;
  char parity = 'E';
  int stop_bits = 1;
  int unit = registers::kDefaultModuleUnitId;
  int sim_unit = registers::kDefaultSimUnitId;
  registers::WordOrder word_order = registers::WordOrder::high_first;
  int timeout_ms = 1000;
};

// No answer, or the link failed (exit code 3).
struct LinkError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The device answered with a Modbus exception.
struct ModbusException : std::runtime_error {
  ModbusException(int code, const std::string& what) : std::runtime_error(what), code(code) {}
  int code;
};

// A sentence for an exception code of a settings write.
std::string exception_sentence(int code);

class Connection {
 public:
  explicit Connection(const ConnectionOptions& options);  // throws LinkError
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  const ConnectionOptions& options() const { return options_; }
  bool is_rtu() const { return !options_.rtu.empty(); }
  std::string describe() const;  // "tcp 127.0.0.1:1502 unit 1"

  // Raw value of one register (throws ModbusException / LinkError).
  std::int64_t read(const registers::Register& reg);
  std::int64_t read(std::string_view name);
  // Raw values of many registers, grouped into as few requests as possible.
  std::map<std::string, std::int64_t> read_many(const std::vector<const registers::Register*>& regs);

  // Words/bits on one table of one unit.
  std::vector<std::uint16_t> read_words(registers::Unit unit, registers::Table table, int start, int count);
  std::vector<std::uint8_t> read_bits(registers::Unit unit, registers::Table table, int start, int count);

  // Writes; 0 when accepted, else the Modbus exception code (LinkError on no answer).
  int write_words(registers::Unit unit, int start, std::span<const std::uint16_t> words);
  int write_bit(registers::Unit unit, int address, bool on);
  int write(const registers::Register& reg, std::int64_t raw);  // coil FC 5, holding FC 16
  int write(std::string_view name, std::int64_t raw);

  // FC 20, reference type 6: `count` records of a file from `record` (count <= 120).
  std::vector<std::uint16_t> read_file_record(int file, int record, int count);

 private:
  void select(registers::Unit unit);
  [[noreturn]] void fail(const std::string& what, int err);
  std::string tls_failure() const;  // " (why the module ended the TLS connection)" or ""

  ConnectionOptions options_;
  std::unique_ptr<TlsTunnel> tunnel_;
  modbus_t* ctx_ = nullptr;
  std::uint16_t tid_ = 0x4000;
};

const registers::Register& register_named(std::string_view name);  // throws std::invalid_argument

}  // namespace homingctl
