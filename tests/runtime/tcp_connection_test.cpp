// One Modbus/TCP connection's state machine (server/tcp_connection.hpp) on a
// fake channel and an injected clock: reads answered on the loop, writes
// handed off it one at a time and in order, frames split across reads, the
// loop's share per turn, a malformed header, and each deadline (idle, frame,
// reply, handshake) closing the connection with its reason.
#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "server/tcp_connection.hpp"
#include "tests/support/captured_log.hpp"

using namespace std::chrono_literals;
using server::TcpConnection;
using Wait = TcpConnection::Wait;

namespace {

struct Wire {
  std::deque<std::vector<std::uint8_t>> incoming;  // each read returns one piece
  bool peer_closed = false;
  bool write_blocked = false;
  bool decrypted_ahead = false;  // the channel holds bytes the socket no longer shows (TLS)
  std::vector<std::uint8_t> sent;
};

class FakeChannel final : public server::ByteChannel {
 public:
  explicit FakeChannel(Wire& wire) : wire_(wire) {}
  int fd() const override { return -1; }
  server::ChannelIo read(std::span<std::uint8_t> out) override {
    if (wire_.incoming.empty())
      return {wire_.peer_closed ? server::ChannelIo::Status::closed : server::ChannelIo::Status::want_read};
    auto& piece = wire_.incoming.front();
    const std::size_t n = std::min(out.size(), piece.size());
    std::copy_n(piece.begin(), n, out.begin());
    piece.erase(piece.begin(), piece.begin() + static_cast<long>(n));
    if (piece.empty()) wire_.incoming.pop_front();
    return {server::ChannelIo::Status::done, n};
  }
  server::ChannelIo write(std::span<const std::uint8_t> bytes) override {
    if (wire_.write_blocked) return {server::ChannelIo::Status::want_write};
    wire_.sent.insert(wire_.sent.end(), bytes.begin(), bytes.end());
    return {server::ChannelIo::Status::done, bytes.size()};
  }
  bool buffered() const override { return wire_.decrypted_ahead && !wire_.incoming.empty(); }

 private:
  Wire& wire_;
};

// Opens at once, or after `steps` want_read answers (a TLS handshake waiting for the client).
class FakeHandshake final : public server::ChannelHandshake {
 public:
  FakeHandshake(Wire& wire, int steps) : wire_(wire), steps_(steps) {}
  server::OpenStep step(server::ClientInfo&) override {
    if (steps_-- > 0) return server::OpenStep::wait_for(server::OpenStep::Kind::want_read);
    return server::OpenStep::opened();
  }
  std::unique_ptr<server::ByteChannel> channel() override { return std::make_unique<FakeChannel>(wire_); }

 private:
  Wire& wire_;
  int steps_;
};

// Answers every request with the function code echoed and one byte: which request it was.
class Counter final : public server::RequestHandler {
 public:
  server::Reply handle(std::uint8_t, std::span<const std::uint8_t> pdu, const server::ClientInfo&) override {
    functions.push_back(pdu[0]);
    return server::Reply{true, {pdu[0], static_cast<std::uint8_t>(functions.size())}};
  }
  void disconnected(const server::ClientInfo&) override {}
  std::vector<std::uint8_t> functions;
};

std::vector<std::uint8_t> frame(std::uint16_t tid, std::vector<std::uint8_t> pdu) {
  std::vector<std::uint8_t> f(7 + pdu.size(), 0);
  f[0] = static_cast<std::uint8_t>(tid >> 8);
  f[1] = static_cast<std::uint8_t>(tid);
  f[4] = static_cast<std::uint8_t>((pdu.size() + 1) >> 8);
  f[5] = static_cast<std::uint8_t>(pdu.size() + 1);
  f[6] = 1;
  std::copy(pdu.begin(), pdu.end(), f.begin() + 7);
  return f;
}
const std::vector<std::uint8_t> kRead{0x03, 0x00, 0x00, 0x00, 0x01};
// FC 23 with a byte count of 255: the longest PDU a request can announce.
constexpr std::size_t kLongestPdu = 10 + 255;
const std::vector<std::uint8_t> kWrite{0x06, 0x00, 0x10, 0x00, 0x01};

// The transaction ids of the reply frames sent, in order.
std::vector<int> replies(const Wire& wire) {
  std::vector<int> tids;
  for (std::size_t at = 0; at + 7 <= wire.sent.size();) {
    tids.push_back((wire.sent[at] << 8) | wire.sent[at + 1]);
    at += 6 + ((wire.sent[at + 4] << 8) | wire.sent[at + 5]);
  }
  return tids;
}

struct Fixture {
  Wire wire;
  Counter handler;
  server::SteadyTime t0 = std::chrono::steady_clock::now();
  TcpConnection connection;
  explicit Fixture(int handshake_steps = 0, int handshake_timeout_ms = 0, int idle_timeout_ms = 60'000)
      : connection(-1, server::ClientInfo(1, server::Transport::tcp, "127.0.0.1:4000"),
                   std::make_unique<FakeHandshake>(wire, handshake_steps), handshake_timeout_ms, idle_timeout_ms, t0) {}
};

}  // namespace

TEST_CASE("a read is answered on the loop, a write goes off it, and nothing after it is read until its reply is in") {
  Fixture f;
  auto bytes = frame(1, kRead);
  for (const auto& next : {frame(2, kWrite), frame(3, kRead)}) bytes.insert(bytes.end(), next.begin(), next.end());
  f.wire.incoming.push_back(bytes);
  REQUIRE(f.connection.advance(f.t0, f.handler) == Wait::off_loop);
  CHECK(f.handler.functions == std::vector<std::uint8_t>{0x03});  // the write was not handled on the loop
  CHECK(f.connection.request().transaction_id == 2);
  CHECK(f.connection.request().pdu == kWrite);
  CHECK(replies(f.wire) == std::vector<int>{1});
  CHECK_FALSE(f.connection.deadline().has_value());  // no timeout while a worker runs it
  CHECK(f.connection.advance(f.t0 + 10s, f.handler) == Wait::off_loop);  // nothing more meanwhile
  CHECK(f.handler.functions.size() == 1);

  f.connection.answered(server::Reply{true, {0x06, 0x00, 0x10, 0x00, 0x01}}, f.t0 + 10s);
  REQUIRE(f.connection.advance(f.t0 + 10s, f.handler) == Wait::read);
  CHECK(replies(f.wire) == std::vector<int>{1, 2, 3});  // in order, the write's in its place
  CHECK(f.handler.functions == std::vector<std::uint8_t>{0x03, 0x03});
}

TEST_CASE("a write the handler can answer without waiting is answered on the loop, in its place") {
  // The handler answers FC 06 at once (a heartbeat while no commit runs), not FC 16.
  class AtOnce final : public server::RequestHandler {
   public:
    server::Reply handle(std::uint8_t, std::span<const std::uint8_t> pdu, const server::ClientInfo&) override {
      return server::Reply{true, {pdu[0]}};
    }
    std::optional<server::Reply> handle_now(std::uint8_t u, std::span<const std::uint8_t> pdu,
                                            const server::ClientInfo& c) override {
      if (pdu[0] != 0x06) return std::nullopt;
      ++now;
      return handle(u, pdu, c);
    }
    void disconnected(const server::ClientInfo&) override {}
    int now = 0;
  } handler;
  Fixture f;
  auto bytes = frame(1, kWrite);
  const auto multiple = frame(2, {0x10, 0x00, 0x10, 0x00, 0x01, 0x02, 0x00, 0x05});
  bytes.insert(bytes.end(), multiple.begin(), multiple.end());
  f.wire.incoming.push_back(bytes);
  REQUIRE(f.connection.advance(f.t0, handler) == Wait::off_loop);
  CHECK(handler.now == 1);
  CHECK(replies(f.wire) == std::vector<int>{1});  // the FC 06 answered on the loop
  CHECK(f.connection.request().transaction_id == 2);  // the FC 16 goes off it
}

TEST_CASE("a frame split across reads is served once whole") {
  Fixture f;
  const auto whole = frame(7, kRead);
  f.wire.incoming.push_back({whole.begin(), whole.begin() + 3});
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
  CHECK(f.handler.functions.empty());
  f.wire.incoming.push_back({whole.begin() + 3, whole.begin() + 9});
  CHECK(f.connection.advance(f.t0 + 300ms, f.handler) == Wait::read);
  CHECK(f.handler.functions.empty());
  f.wire.incoming.push_back({whole.begin() + 9, whole.end()});
  CHECK(f.connection.advance(f.t0 + 600ms, f.handler) == Wait::read);
  CHECK(replies(f.wire) == std::vector<int>{7});
}

TEST_CASE("a frame not whole within the frame timeout of its first byte closes the connection") {
  Fixture f;
  const auto whole = frame(7, kRead);
  f.wire.incoming.push_back({whole.begin(), whole.begin() + 9});
  REQUIRE(f.connection.advance(f.t0, f.handler) == Wait::read);
  REQUIRE(f.connection.deadline() == f.t0 + std::chrono::milliseconds(server::kFrameTimeoutMs));
  CHECK(f.connection.advance(f.t0 + 999ms, f.handler) == Wait::read);
  CHECK(f.connection.advance(f.t0 + 1000ms, f.handler) == Wait::closed);
  CHECK(f.connection.end_reason().find("incomplete frame") != std::string::npos);
  CHECK(f.handler.functions.empty());
}

TEST_CASE("a connection that sends nothing within the idle timeout is closed with that reason") {
  Fixture f(0, 0, 2000);
  REQUIRE(f.connection.advance(f.t0, f.handler) == Wait::read);
  f.wire.incoming.push_back(frame(1, kRead));
  REQUIRE(f.connection.advance(f.t0 + 1500ms, f.handler) == Wait::read);  // a request: the idle time starts again
  CHECK(f.connection.deadline() == f.t0 + 3500ms);
  CHECK(f.connection.advance(f.t0 + 3400ms, f.handler) == Wait::read);
  CHECK(f.connection.advance(f.t0 + 3500ms, f.handler) == Wait::closed);
  CHECK(f.connection.end_reason() == "idle timeout (--idle-timeout-s)");
}

TEST_CASE("a reply the client does not take within the frame timeout closes the connection") {
  Fixture f;
  f.wire.write_blocked = true;
  f.wire.incoming.push_back(frame(1, kRead));
  f.wire.incoming.push_back(frame(2, kRead));
  REQUIRE(f.connection.advance(f.t0, f.handler) == Wait::write);
  CHECK(f.handler.functions.size() == 1);  // the next request waits for the reply to leave
  CHECK(f.connection.advance(f.t0 + 999ms, f.handler) == Wait::write);
  CHECK(f.connection.advance(f.t0 + 1000ms, f.handler) == Wait::closed);
  CHECK(f.connection.end_reason() == "a reply not taken within 1000 ms (the client reads nothing)");
}

TEST_CASE("a malformed MBAP header closes the connection and is not served") {
  Fixture f;
  f.wire.incoming.push_back({0x00, 0x01, 0x00, 0x00, 0x01, 0x2C, 0x01});  // length 300
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::closed);
  CHECK(f.connection.end_reason() == "malformed MBAP header");
  CHECK(f.handler.functions.empty());
}

TEST_CASE("a TLS client or a web browser on the plain Modbus TCP port is told apart in the log and closed") {
  const test_support::CapturedLog log;
  const auto logged = [&] { return log.text(); };
  Fixture tls;
  // A ClientHello's record header: handshake (0x16), TLS 1.0 record version, length, type 1.
  tls.wire.incoming.push_back({0x16, 0x03, 0x01, 0x02, 0x00, 0x01, 0x00, 0x01, 0xfc, 0x03, 0x03});
  CHECK(tls.connection.advance(tls.t0, tls.handler) == Wait::closed);
  CHECK(tls.handler.functions.empty());
  CHECK(logged().find("not Modbus but a TLS handshake: this port serves plain Modbus TCP") != std::string::npos);
  CHECK(logged().find("--tls port") != std::string::npos);
  Fixture web;
  const std::string get = "GET / HTTP/1.1\r\nHost: 127.0.0.1:1502\r\n\r\n";
  web.wire.incoming.push_back(std::vector<std::uint8_t>(get.begin(), get.end()));
  CHECK(web.connection.advance(web.t0, web.handler) == Wait::closed);
  CHECK(logged().find("not Modbus but an HTTP request") != std::string::npos);
  // A Modbus frame whose transaction id happens to be 0x1603 is no TLS handshake.
  Fixture modbus;
  modbus.wire.incoming.push_back({0x16, 0x03, 0x00, 0x00, 0x01, 0x2C, 0x01});
  CHECK(modbus.connection.advance(modbus.t0, modbus.handler) == Wait::closed);
  CHECK(logged().find("MBAP protocol 0 length 300") != std::string::npos);
  // Garbage that is neither is named by its header fields, as before.
  Fixture junk;
  junk.wire.incoming.push_back({0x00, 0x01, 0x00, 0x07, 0x00, 0x06, 0x01});
  CHECK(junk.connection.advance(junk.t0, junk.handler) == Wait::closed);
  CHECK(logged().find("MBAP protocol 7 length 6") != std::string::npos);
}

TEST_CASE("a write longer than the standard's largest frame is read whole and handed on, so that it can be refused "
          "with exception 03, and the stream stays in step") {
  Fixture f;
  // FC 16 of 124 registers, all their data: a PDU of 254 bytes (MBAP length 255).
  std::vector<std::uint8_t> too_many{0x10, 0x00, 0x64, 0x00, 124, 248};
  too_many.resize(6 + 248, 0);
  auto bytes = frame(1, too_many);
  const auto next = frame(2, kRead);
  bytes.insert(bytes.end(), next.begin(), next.end());
  f.wire.incoming.push_back(bytes);
  REQUIRE(f.connection.advance(f.t0, f.handler) == Wait::off_loop);
  CHECK(f.connection.request().transaction_id == 1);
  CHECK(f.connection.request().pdu == too_many);
  // One byte past the longest request any function code can frame: garbage.
  Fixture g;
  std::vector<std::uint8_t> garbage{0x17};
  garbage.resize(kLongestPdu + 1, 0);
  g.wire.incoming.push_back(frame(1, garbage));
  CHECK(g.connection.advance(g.t0, g.handler) == Wait::closed);
  CHECK(g.connection.end_reason() == "malformed MBAP header");
}

TEST_CASE("a client that pipelines many requests gets its share of a turn, then the loop serves the others") {
  Fixture f;
  std::vector<std::uint8_t> bytes;
  for (int i = 0; i < 40; ++i) {
    const auto next = frame(static_cast<std::uint16_t>(i), kRead);
    bytes.insert(bytes.end(), next.begin(), next.end());
  }
  f.wire.incoming.push_back(bytes);
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::again);
  CHECK(f.handler.functions.size() == static_cast<std::size_t>(server::kFramesPerTurn));
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::again);
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
  CHECK(f.handler.functions.size() == 40);
  CHECK(replies(f.wire).size() == 40);
}

TEST_CASE("a client that sends its next request the moment it has its reply waits for the next turn") {
  // Over loopback a quick client's next request is often in before the loop
  // reads again: served at once, one connection could take the loop for
  // itself while the others wait (the 64-client benchmark's tail).
  Fixture f;
  f.wire.incoming.push_back(frame(1, kRead));
  f.wire.incoming.push_back(frame(2, kRead));
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
  CHECK(replies(f.wire) == std::vector<int>{1});
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
  CHECK(replies(f.wire) == std::vector<int>{1, 2});
}

TEST_CASE("a channel holding bytes the socket no longer shows asks the loop to come back without waiting") {
  Fixture f;
  f.wire.decrypted_ahead = true;
  f.wire.incoming.push_back(frame(1, kRead));
  f.wire.incoming.push_back(frame(2, kRead));
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::again);
  CHECK(replies(f.wire) == std::vector<int>{1});
  CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
  CHECK(replies(f.wire) == std::vector<int>{1, 2});
}

TEST_CASE("a handshake not finished within its timeout refuses the connection, one in time serves it") {
  SECTION("stalled") {
    Fixture f(1000, 3000);
    CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
    CHECK(f.connection.advance(f.t0 + 2999ms, f.handler) == Wait::read);
    CHECK(f.connection.advance(f.t0 + 3000ms, f.handler) == Wait::closed);
    CHECK(f.connection.refused());
    CHECK_FALSE(f.connection.opened());
    CHECK(f.connection.end_reason() == "TLS handshake not finished within 3000 ms of connecting");
  }
  SECTION("in time") {
    Fixture f(2, 3000);
    f.wire.incoming.push_back(frame(5, kRead));
    CHECK(f.connection.advance(f.t0, f.handler) == Wait::read);
    CHECK(f.connection.advance(f.t0 + 100ms, f.handler) == Wait::read);
    CHECK_FALSE(f.connection.opened());
    CHECK(f.connection.advance(f.t0 + 200ms, f.handler) == Wait::read);
    CHECK(f.connection.opened());
    CHECK(replies(f.wire) == std::vector<int>{5});
  }
}

TEST_CASE("only writes may wait: reads, diagnostics and identification are answered on the loop") {
  for (const std::uint8_t fc : {0x05, 0x06, 0x0F, 0x10, 0x16, 0x17}) CHECK(server::may_wait(fc));
  for (const std::uint8_t fc : {0x01, 0x02, 0x03, 0x04, 0x07, 0x08, 0x11, 0x14, 0x2B}) CHECK_FALSE(server::may_wait(fc));
}
