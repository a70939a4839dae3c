// Line diagnostics (function 08) and report server id (function 17) as a
// commissioning engineer uses them: over TCP and over an RTU line (a pty
// pair), with counters kept per transport that move when a frame with a bad
// CRC, a frame for another unit or a broadcast crosses the line.
#include <catch2/catch.hpp>

#include <poll.h>
#include <sys/socket.h>

#include "daemon.hpp"

using namespace e2e;

namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes diag_pdu(std::uint16_t sub, std::uint16_t data = 0) {
  return {0x08, static_cast<std::uint8_t>(sub >> 8), static_cast<std::uint8_t>(sub), static_cast<std::uint8_t>(data >> 8),
          static_cast<std::uint8_t>(data)};
}

// The 16-bit answer of a counter sub-function, or -1.
int counter_of(const Bytes& reply, std::uint16_t sub) {
  if (reply.size() != 5 || reply[0] != 0x08 || ((reply[1] << 8) | reply[2]) != sub) return -1;
  return (reply[3] << 8) | reply[4];
}

int tcp_counter(int port, std::uint16_t sub) { return counter_of(raw_tcp_transaction(port, 1, diag_pdu(sub)), sub); }

std::uint16_t crc16(const Bytes& bytes) {
  std::uint16_t crc = 0xFFFF;
  for (std::uint8_t b : bytes) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
  }
  return crc;
}

// One RTU exchange framed here (libmodbus cannot parse a function 08 reply):
// the reply PDU after its unit id and CRC were checked, empty when nothing came.
Bytes rtu_exchange(Client& rtu, std::uint8_t unit, const Bytes& pdu, bool expect_reply = true) {
  const int fd = modbus_get_socket(rtu.ctx());
  Bytes frame{unit};
  frame.insert(frame.end(), pdu.begin(), pdu.end());
  const std::uint16_t crc = crc16(frame);
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  modbus_flush(rtu.ctx());
  REQUIRE(::write(fd, frame.data(), frame.size()) == static_cast<ssize_t>(frame.size()));
  Bytes reply;
  // The reply's bytes follow each other closely; 150 ms of silence ends it.
  for (int wait_ms = expect_reply ? 2000 : 300;; wait_ms = 150) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, wait_ms) <= 0) break;
    std::uint8_t buf[256];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) break;
    reply.insert(reply.end(), buf, buf + n);
  }
  if (reply.size() < 4) return {};
  const Bytes body(reply.begin(), reply.end() - 2);
  const std::uint16_t got = static_cast<std::uint16_t>(reply[reply.size() - 2] | (reply[reply.size() - 1] << 8));
  REQUIRE(got == crc16(body));
  REQUIRE(body[0] == unit);
  return Bytes(body.begin() + 1, body.end());
}

int rtu_counter(Client& rtu, std::uint16_t sub) { return counter_of(rtu_exchange(rtu, 1, diag_pdu(sub)), sub); }

std::string server_id_text(const Bytes& reply) {
  // 17, byte count, server id, run indicator, text
  if (reply.size() < 4 || reply[0] != 0x11 || reply[1] != reply.size() - 2) return {};
  return std::string(reply.begin() + 4, reply.end());
}

}  // namespace

TEST_CASE("over TCP function 08 echoes query data, counts requests and exceptions, and clears its counters") {
  Daemon d;
  // 00: the data comes back as sent.
  Bytes echo{0x08, 0x00, 0x00, 0x12, 0x34, 0xAB, 0xCD};
  CHECK(raw_tcp_transaction(d.port(), 1, echo) == echo);
  // 0A: cleared, the request echoed.
  CHECK(raw_tcp_transaction(d.port(), 1, diag_pdu(0x0A)) == diag_pdu(0x0A));
  const auto& map_version = reg("status.map_version");
  const Bytes good_read{0x04, static_cast<std::uint8_t>(map_version.address >> 8),
                        static_cast<std::uint8_t>(map_version.address), 0, 1};
  for (int i = 0; i < 3; ++i) CHECK(raw_tcp_transaction(d.port(), 1, good_read).size() == 4);
  CHECK(raw_tcp_transaction(d.port(), 1, {0x03, 0xFF, 0x00, 0x00, 0x01}) == Bytes{0x83, 0x02});  // nothing there
  // Every request since the clear counts, the one asking included.
  CHECK(tcp_counter(d.port(), 0x0B) == 5);  // bus messages
  CHECK(tcp_counter(d.port(), 0x0E) == 6);  // server messages
  CHECK(tcp_counter(d.port(), 0x0D) == 1);  // exceptions
  CHECK(tcp_counter(d.port(), 0x0C) == 0);  // communication errors
  CHECK(tcp_counter(d.port(), 0x0F) == 0);  // no response
  CHECK(tcp_counter(d.port(), 0x10) == 0);  // NAKs: never sent
  CHECK(tcp_counter(d.port(), 0x11) == 0);  // busy
  CHECK(tcp_counter(d.port(), 0x12) == 0);  // overruns

  // A malformed MBAP header (protocol 1) is a communication error: the
  // connection closes, the counter moves.
  {
    Client c = Client::tcp(d.port());
    const Bytes bad{0x00, 0x01, 0x00, 0x01, 0x00, 0x06, 0x01, 0x04, 0x00, 0x00, 0x00, 0x01};
    REQUIRE(::send(modbus_get_socket(c.ctx()), bad.data(), bad.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bad.size()));
    REQUIRE(wait_until([&] { return tcp_counter(d.port(), 0x0C) == 1; }, 3s));
  }
  // 01 (restart communications) clears the counters too.
  CHECK(raw_tcp_transaction(d.port(), 1, diag_pdu(0x01, 0xFF00)) == diag_pdu(0x01, 0xFF00));
  CHECK(tcp_counter(d.port(), 0x0C) == 0);
  CHECK(tcp_counter(d.port(), 0x0E) == 2);
  // An unsupported sub-function is exception 01; the simulator unit has no line diagnostics.
  CHECK(raw_tcp_transaction(d.port(), 1, diag_pdu(0x04)) == Bytes{0x88, 0x01});
  CHECK(raw_tcp_transaction(d.port(), 247, diag_pdu(0x00)) == Bytes{0x88, 0x01});
}

TEST_CASE("function 17 reports the unit id, run indicator ON and the product, version and machine name") {
  Daemon d({.extra = {"--machine-name", "Gantry mill 3"}});
  const Bytes reply = raw_tcp_transaction(d.port(), 1, {0x11});
  REQUIRE(reply.size() >= 4);
  CHECK(reply[2] == 1);     // the unit id
  CHECK(reply[3] == 0xFF);  // running
  CHECK(server_id_text(reply) == std::string("HM-6 ") + HOMING_VERSION + " Gantry mill 3");
  // The machine's name is device identification object 6 too.
  const Bytes one = raw_tcp_transaction(d.port(), 1, {0x2B, 0x0E, 0x04, 0x06});
  REQUIRE(one.size() >= 9);
  CHECK(std::string(one.begin() + 9, one.end()) == "Gantry mill 3");
  // The simulator unit is no device of its own: neither identifies it.
  CHECK(raw_tcp_transaction(d.port(), 247, {0x11}) == Bytes{0x91, 0x01});
  CHECK(raw_tcp_transaction(d.port(), 247, {0x2B, 0x0E, 0x01, 0x00}) == Bytes{0xAB, 0x01});
}

TEST_CASE("over RTU function 08 counts bad CRCs, other units' frames and broadcasts apart from TCP") {
  PtyPair pty;
  // Debug logging: the module logs the bad frame it drops, which the test waits for.
  Daemon d({.extra = {"--rtu", pty.server_end(), "--baud", "19200", "--parity", "E", "--log-level", "debug"}});
  Client rtu = Client::rtu(pty.client_end(), 19200, 'E');
  REQUIRE(rtu.read("status.map_version") == registers::kMapVersion);
  // Both transports start from zero here.
  CHECK(rtu_exchange(rtu, 1, diag_pdu(0x0A)) == diag_pdu(0x0A));
  CHECK(raw_tcp_transaction(d.port(), 1, diag_pdu(0x0A)) == diag_pdu(0x0A));

  // A frame whose CRC is wrong.
  const int fd = modbus_get_socket(rtu.ctx());
  const std::uint8_t bad_crc[] = {0x01, 0x03, 0x00, 0x00, 0x00, 0x01, 0xDE, 0xAD};
  REQUIRE(::write(fd, bad_crc, sizeof bad_crc) == static_cast<ssize_t>(sizeof bad_crc));
  // Taken off the line before the next request (whose flush would drop its
  // bytes from the pty unread).
  REQUIRE(wait_until([&] { return d.log().find("rtu: bad frame (CRC), 1 so far") != std::string::npos; }, 10s));
  // After a bad frame the module ignores the line until 100 ms of silence: a
  // request before that gets no answer and counts nowhere. The first one it
  // answers again (the communication-error count) says the line is its own again.
  Bytes comm_errors;
  REQUIRE(wait_until([&] { return !(comm_errors = rtu_exchange(rtu, 1, diag_pdu(0x0C))).empty(); }, 20s, 0ms));
  CHECK(counter_of(comm_errors, 0x0C) == 1);
  // A read for unit 5 (another device on the bus): silence from the module.
  CHECK(rtu_exchange(rtu, 5, {0x03, 0x00, 0x00, 0x00, 0x01}, false).empty());
  // A broadcast write: applied, never answered.
  const auto& jog = reg("axis.x.jog_feedrate");
  CHECK(rtu_exchange(rtu, 0, {0x06, static_cast<std::uint8_t>(jog.address >> 8), static_cast<std::uint8_t>(jog.address),
                              0x04, 0xD2},
                     false)
            .empty());

  CHECK(rtu_counter(rtu, 0x0B) == 5);  // bus: bad CRC, the first 0C, unit 5, broadcast, this request
  CHECK(rtu_counter(rtu, 0x0C) == 1);  // the bad CRC
  CHECK(rtu_counter(rtu, 0x0E) == 5);  // for this module: the first 0C, broadcast, 0B, 0C, this request
  CHECK(rtu_counter(rtu, 0x0F) == 1);  // the broadcast went unanswered
  CHECK(rtu_counter(rtu, 0x0D) == 0);
  // TCP saw none of it: only its own request.
  CHECK(tcp_counter(d.port(), 0x0E) == 1);
  CHECK(tcp_counter(d.port(), 0x0C) == 0);

  // Device identification over the serial line (libmodbus could not frame it).
  const Bytes ident = rtu_exchange(rtu, 1, {0x2B, 0x0E, 0x04, 0x02});
  REQUIRE(ident.size() >= 9);
  CHECK(std::string(ident.begin() + 9, ident.end()) == HOMING_VERSION);
  // Report server id over the serial line.
  const Bytes id = rtu_exchange(rtu, 1, {0x11});
  CHECK(server_id_text(id).rfind(std::string("HM-6 ") + HOMING_VERSION, 0) == 0);
}
