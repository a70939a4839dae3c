#include "connection.hpp"

#include <arpa/inet.h>
#include <fmt/format.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "registers/lookup.hpp"
#include "host_port.hpp"
#include "tls/address.hpp"
#include "tls_tunnel.hpp"

namespace homingctl {

using registers::Register;
using registers::Table;
using registers::Unit;

const Register& register_named(std::string_view name) {
  const Register* r = registers::find_register(name);
  if (!r) throw std::invalid_argument(fmt::format("no register named '{}' (see hmi_maps/registers.md)", name));
  return *r;
}

std::string exception_sentence(int code) {
  switch (code) {
    case 1:
      return "exception 01: this client may not write that (its certificate's role or --write-allow; the module's "
             "log names which), or the module does not know the function";
    case 2: return "exception 02: address not writable (read-only register, unmapped address or half of a 32-bit value)";
    case 3: return "exception 03: a value is out of range or the settings cannot work together (the module's log names it)";
    case 4: return "exception 04: the module could not store the setting (disk full or read-only?); nothing changed";
    case 6: return "exception 06: a homing cycle is running: settings cannot change now; wait for it to end or abort it";
    case 11: return "exception 0B: no device answers at this unit id (check --unit / --sim-unit)";
    default: return fmt::format("exception {:02X}", code);
  }
}

namespace {

int exception_of(int err) {
  if (err > MODBUS_ENOBASE && err <= EMBXGTAR) return err - MODBUS_ENOBASE;
  return 0;
}

// Exception 0B (gateway target failed to respond) means no device answered at
// that unit id: for the user that is "no answer", exit 3, like a dead link.
int no_answer_at_unit(const std::string& what, int ex) {
  if (ex == 11) throw LinkError(fmt::format("{}: {}", what, exception_sentence(ex)));
  return ex;
}

// The module's IPv4 address for HOST, a name or an address, as --tls finds
// it: libmodbus's TCP client reads HOST with inet_addr(), which takes a name
// for 255.255.255.255 and fails with "Network is unreachable".
std::string ipv4_of(const std::string& host, const std::string& where) {
  const auto ip = tls::resolve_ipv4(host);
  if (!ip) throw LinkError(fmt::format("cannot connect to {}: {}", where, ip.error()));
  char text[INET_ADDRSTRLEN] = {};
  ::inet_ntop(AF_INET, &*ip, text, sizeof text);
  return text;
}

std::uint16_t crc16(const std::uint8_t* p, std::size_t n) {
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int b = 0; b < 8; ++b) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
  }
  return crc;
}

}  // namespace

Connection::Connection(const ConnectionOptions& options) : options_(options) {
  if (!options_.rtu.empty()) {
    ctx_ = modbus_new_rtu(options_.rtu.c_str(), options_.baud, options_.parity, 8, options_.stop_bits);
  } else if (!options_.tls.empty()) {
    tunnel_ = std::make_unique<TlsTunnel>(
        TlsOptions{options_.tls, options_.cert, options_.key, options_.ca, std::max(3000, options_.timeout_ms)});
    ctx_ = modbus_new_tcp("127.0.0.1", 802);  // never connects: its socket is the tunnel's
  } else {
    auto [host, port] = host_and_port(options_.tcp, 502, "--tcp");
    ctx_ = modbus_new_tcp(ipv4_of(host, describe()).c_str(), port);
  }
  if (!ctx_) throw LinkError(fmt::format("cannot set up {}: {}", describe(), modbus_strerror(errno)));
  const int ms = std::max(1, options_.timeout_ms);
  modbus_set_response_timeout(ctx_, static_cast<std::uint32_t>(ms / 1000), static_cast<std::uint32_t>((ms % 1000) * 1000));
  if (tunnel_) {
    modbus_set_socket(ctx_, tunnel_->take_modbus_end());
  } else if (modbus_connect(ctx_) != 0) {
    const int e = errno;
    modbus_free(ctx_);
    ctx_ = nullptr;
    throw LinkError(fmt::format("cannot connect to {}: {}", describe(), modbus_strerror(e)));
  }
  modbus_set_slave(ctx_, options_.unit);
}

Connection::~Connection() {
  if (ctx_) {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
}

std::string Connection::describe() const {
  if (!options_.rtu.empty())
    return fmt::format("rtu {} {} {}{}{} unit {}", options_.rtu, options_.baud, 8, options_.parity, options_.stop_bits,
                       options_.unit);
  if (!options_.tls.empty()) return fmt::format("tls {} unit {}", options_.tls, options_.unit);
  // The port tried, also when the user gave none (Modbus's 502).
  const bool has_port = options_.tcp.find(':') != std::string::npos;
  return fmt::format("tcp {}{} unit {}", options_.tcp, has_port ? "" : ":502", options_.unit);
}

void Connection::select(Unit unit) {
  modbus_set_slave(ctx_, unit == Unit::simulator ? options_.sim_unit : options_.unit);
}

void Connection::fail(const std::string& what, int err) {
  if (const int ex = exception_of(err)) {
    no_answer_at_unit(what, ex);
    throw ModbusException(ex, fmt::format("{}: {}", what, exception_sentence(ex)));
  }
  if (is_rtu()) modbus_flush(ctx_);
  throw LinkError(fmt::format("{}: no valid answer from {}: {}{}", what, describe(), modbus_strerror(err), tls_failure()));
}

std::string Connection::tls_failure() const {
  const std::string why = tunnel_ ? tunnel_->failure() : std::string();
  return why.empty() ? why : " (" + why + ")";
}

std::vector<std::uint16_t> Connection::read_words(Unit unit, Table table, int start, int count) {
  select(unit);
  std::vector<std::uint16_t> w(static_cast<std::size_t>(count));
  for (int attempt = 0;; ++attempt) {
    const int rc = table == Table::holding_register ? modbus_read_registers(ctx_, start, count, w.data())
                                                    : modbus_read_input_registers(ctx_, start, count, w.data());
    if (rc == count) return w;
    const int err = errno;
    if (rc >= 0 || exception_of(err) || attempt >= 1)
      fail(fmt::format("reading {} {}..{}", registers::table_name(table), start, start + count - 1), err);
    if (is_rtu()) modbus_flush(ctx_);
  }
}

std::vector<std::uint8_t> Connection::read_bits(Unit unit, Table table, int start, int count) {
  select(unit);
  std::vector<std::uint8_t> b(static_cast<std::size_t>(count));
  for (int attempt = 0;; ++attempt) {
    const int rc = table == Table::coil ? modbus_read_bits(ctx_, start, count, b.data())
                                        : modbus_read_input_bits(ctx_, start, count, b.data());
    if (rc == count) return b;
    const int err = errno;
    if (rc >= 0 || exception_of(err) || attempt >= 1)
      fail(fmt::format("reading {} {}..{}", registers::table_name(table), start, start + count - 1), err);
    if (is_rtu()) modbus_flush(ctx_);
  }
}

std::int64_t Connection::read(const Register& reg) {
  return read_many({&reg}).begin()->second;
}
std::int64_t Connection::read(std::string_view name) { return read(register_named(name)); }

std::map<std::string, std::int64_t> Connection::read_many(const std::vector<const Register*>& input) {
  std::vector<const Register*> regs = input;
  std::sort(regs.begin(), regs.end(), [](const Register* a, const Register* b) {
    return std::tie(a->unit, a->table, a->address) < std::tie(b->unit, b->table, b->address);
  });
  regs.erase(std::unique(regs.begin(), regs.end()), regs.end());
  std::map<std::string, std::int64_t> out;
  std::size_t i = 0;
  while (i < regs.size()) {
    const Register& first = *regs[i];
    const bool bits = first.table == Table::coil || first.table == Table::discrete_input;
    const std::uint32_t limit = bits ? 2000 : 125, max_gap = bits ? 64 : 40;
    std::size_t j = i + 1;
    std::uint32_t end = first.end();
    while (j < regs.size() && regs[j]->unit == first.unit && regs[j]->table == first.table &&
           regs[j]->end() - first.address <= limit && regs[j]->address <= end + max_gap) {
      end = std::max(end, regs[j]->end());
      ++j;
    }
    const int count = static_cast<int>(end - first.address);
    if (bits) {
      const auto b = read_bits(first.unit, first.table, first.address, count);
      for (std::size_t k = i; k < j; ++k) out[regs[k]->name()] = b[regs[k]->address - first.address];
    } else {
      const auto w = read_words(first.unit, first.table, first.address, count);
      for (std::size_t k = i; k < j; ++k) {
        const Register& r = *regs[k];
        out[r.name()] = registers::decode_words(
            r, std::span<const std::uint16_t>(w.data() + (r.address - first.address), r.words()), options_.word_order);
      }
    }
    i = j;
  }
  return out;
}

int Connection::write_words(Unit unit, int start, std::span<const std::uint16_t> words) {
  select(unit);
  const int rc = modbus_write_registers(ctx_, start, static_cast<int>(words.size()), words.data());
  if (rc >= 0) return 0;
  const int err = errno;
  if (const int ex = exception_of(err)) return no_answer_at_unit(fmt::format("writing holding registers {}", start), ex);
  if (is_rtu()) modbus_flush(ctx_);
  throw LinkError(fmt::format("writing holding registers {}..{}: no valid answer from {}: {}{}", start,
                              start + static_cast<int>(words.size()) - 1, describe(), modbus_strerror(err),
                              tls_failure()));
}

int Connection::write_bit(Unit unit, int address, bool on) {
  select(unit);
  const int rc = modbus_write_bit(ctx_, address, on ? 1 : 0);
  if (rc >= 0) return 0;
  const int err = errno;
  if (const int ex = exception_of(err)) return no_answer_at_unit(fmt::format("writing coil {}", address), ex);
  if (is_rtu()) modbus_flush(ctx_);
  throw LinkError(fmt::format("writing coil {}: no valid answer from {}: {}{}", address, describe(),
                              modbus_strerror(err), tls_failure()));
}

int Connection::write(const Register& reg, std::int64_t raw) {
  if (reg.table == Table::coil) return write_bit(reg.unit, reg.address, raw != 0);
  std::uint16_t words[2] = {0, 0};
  registers::encode_words(reg, raw, options_.word_order, std::span<std::uint16_t>(words, reg.words()));
  return write_words(reg.unit, reg.address, std::span<const std::uint16_t>(words, reg.words()));
}
int Connection::write(std::string_view name, std::int64_t raw) { return write(register_named(name), raw); }

// FC 20 framed by hand: libmodbus 3.1.6 sizes a confirmation of an unknown
// function as one byte after the function code, so it would leave the records
// in the socket (TCP) or fail the CRC (RTU). The request goes out through
// modbus_send_raw_request (MBAP or CRC added by libmodbus), the answer is read
// here from the same descriptor and checked.
std::vector<std::uint16_t> Connection::read_file_record(int file, int record, int count) {
  if (count < 1 || count > 120) throw std::invalid_argument("read_file_record: 1..120 records per request");
  select(Unit::module);
  const auto unit = static_cast<std::uint8_t>(options_.unit);
  const std::uint8_t req[] = {unit, 20, 7, 6,
                              static_cast<std::uint8_t>(file >> 8), static_cast<std::uint8_t>(file & 0xFF),
                              static_cast<std::uint8_t>(record >> 8), static_cast<std::uint8_t>(record & 0xFF),
                              static_cast<std::uint8_t>(count >> 8), static_cast<std::uint8_t>(count & 0xFF)};
  const std::string what = fmt::format("reading trace file {} records {}..{}", file, record, record + count - 1);
  if (modbus_send_raw_request(ctx_, req, sizeof req) < 0) fail(what, errno);
  const int fd = modbus_get_socket(ctx_);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(options_.timeout_ms);
  std::vector<std::uint8_t> got;
  auto need = [&](std::size_t n) {
    while (got.size() < n) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()).count();
      if (left <= 0) fail(what, ETIMEDOUT);
      pollfd p{fd, POLLIN, 0};
      const int r = ::poll(&p, 1, static_cast<int>(left));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) fail(what, ETIMEDOUT);
      std::uint8_t buf[512];
      const ssize_t k = ::read(fd, buf, std::min<std::size_t>(sizeof buf, n - got.size()));
      if (k <= 0) fail(what, k == 0 ? ECONNRESET : errno);
      got.insert(got.end(), buf, buf + k);
    }
  };
  std::size_t pdu_at = 0, pdu_len = 0;
  if (!is_rtu()) {
    need(7);
    const std::size_t len = (std::size_t{got[4]} << 8) | got[5];
    if (got[2] != 0 || got[3] != 0 || len < 2) fail(what, EMBBADDATA);
    need(6 + len);
    if (got[6] != unit) fail(what, EMBBADSLAVE);
    pdu_at = 7;
    pdu_len = len - 1;
  } else {
    need(3);
    if (got[0] != unit) {
      modbus_flush(ctx_);
      fail(what, EMBBADSLAVE);
    }
    const std::size_t total = (got[1] & 0x80) ? 5 : 3 + std::size_t{got[2]} + 2;
    need(total);
    const std::uint16_t crc = crc16(got.data(), total - 2);
    if ((got[total - 2] | (got[total - 1] << 8)) != crc) {
      modbus_flush(ctx_);
      fail(what, EMBBADCRC);
    }
    pdu_at = 1;
    pdu_len = total - 3;
  }
  const std::uint8_t* pdu = got.data() + pdu_at;
  if (pdu_len >= 2 && pdu[0] == (20 | 0x80)) {
    const int ex = no_answer_at_unit(what, pdu[1]);
    throw ModbusException(ex, fmt::format("{}: exception {:02X}{}", what, ex,
                                          ex == 2 ? " (no such records: the trace is shorter)" : ""));
  }
  // fc, byte count, sub-response: length, type 6, data
  const std::size_t want = 2 + 2 + 2 * static_cast<std::size_t>(count);
  if (pdu_len != want || pdu[0] != 20 || pdu[1] != want - 2 || pdu[2] != 1 + 2 * count || pdu[3] != 6)
    fail(what, EMBBADDATA);
  std::vector<std::uint16_t> words(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i)
    words[static_cast<std::size_t>(i)] = static_cast<std::uint16_t>((pdu[4 + 2 * i] << 8) | pdu[5 + 2 * i]);
  return words;
}

}  // namespace homingctl
