// The RTU framer alone (server/rtu_framer.hpp): where frames end on a serial
// line, for the functions libmodbus cannot frame (08, 20, 43) too.
#include <catch2/catch.hpp>

#include <vector>

#include "server/pdu.hpp"
#include "server/rtu_framer.hpp"

namespace {

using Bytes = std::vector<std::uint8_t>;
using server::RtuFramer;

Bytes with_crc(Bytes frame) {
  const std::uint16_t crc = server::crc16(frame);
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  return frame;
}

// Feeds bytes, then silence; every result in order.
std::vector<RtuFramer::Result> feed(RtuFramer& f, const Bytes& bytes, bool then_silence = true) {
  std::vector<RtuFramer::Result> out;
  for (std::uint8_t b : bytes)
    if (auto r = f.push(b)) out.push_back(*r);
  if (then_silence)
    if (auto r = f.silence()) out.push_back(*r);
  return out;
}

}  // namespace

TEST_CASE("rtu framer: a diagnostics request for this module is one frame, answered at once") {
  RtuFramer f(1);
  const Bytes req = with_crc({1, 0x08, 0x00, 0x0B, 0x00, 0x00});
  const auto r = feed(f, req, false);
  REQUIRE(r.size() == 1);
  CHECK(r[0].event == RtuFramer::Event::frame);
  CHECK(r[0].frame == req);
  CHECK_FALSE(f.pending());
}

TEST_CASE("rtu framer: return query data with several words grows until its CRC matches") {
  RtuFramer f(1);
  const Bytes req = with_crc({1, 0x08, 0x00, 0x00, 0x12, 0x34, 0xAB, 0xCD, 0x00, 0x01});
  const auto r = feed(f, req);
  REQUIRE(r.size() == 1);
  CHECK(r[0].frame == req);
}

TEST_CASE("rtu framer: device identification, file record and report server id frame by their own lengths") {
  for (const Bytes& body : {Bytes{1, 0x2B, 0x0E, 0x01, 0x00}, Bytes{1, 0x14, 0x07, 0x06, 0x00, 0x01, 0x00, 0x00, 0x00, 0x02},
                            Bytes{1, 0x11}, Bytes{1, 0x10, 0x00, 0x64, 0x00, 0x02, 0x04, 0x00, 0x00, 0x0B, 0xB8}}) {
    RtuFramer f(1);
    const Bytes req = with_crc(body);
    INFO("FC " << int(body[1]));
    const auto r = feed(f, req, false);
    REQUIRE(r.size() == 1);
    CHECK(r[0].frame == req);
  }
}

TEST_CASE("rtu framer: two requests back to back are two frames") {
  RtuFramer f(1);
  const Bytes a = with_crc({1, 0x03, 0x00, 0x00, 0x00, 0x01});
  const Bytes b = with_crc({1, 0x08, 0x00, 0x0E, 0x00, 0x00});
  Bytes both = a;
  both.insert(both.end(), b.begin(), b.end());
  const auto r = feed(f, both);
  REQUIRE(r.size() == 2);
  CHECK(r[0].frame == a);
  CHECK(r[1].frame == b);
}

TEST_CASE("rtu framer: a bad CRC is one error, and the next frame after silence is read normally") {
  RtuFramer f(1);
  const auto r = feed(f, {1, 0x03, 0x00, 0x00, 0x00, 0x01, 0xDE, 0xAD, 0x55, 0xAA});
  REQUIRE(r.size() == 1);
  CHECK(r[0].event == RtuFramer::Event::bad_crc);
  const Bytes good = with_crc({1, 0x03, 0x00, 0x00, 0x00, 0x01});
  const auto next = feed(f, good, false);
  REQUIRE(next.size() == 1);
  CHECK(next[0].frame == good);
}

TEST_CASE("rtu framer: a master's retry right after a corrupted request is a frame, with no silence between") {
  RtuFramer f(1);
  const Bytes good = with_crc({1, 0x04, 0x00, 0x00, 0x00, 0x02});
  Bytes corrupted = good;
  corrupted[5] ^= 0x10;  // one bit flipped on the line
  Bytes line = corrupted;
  line.insert(line.end(), good.begin(), good.end());
  const auto r = feed(f, line, false);
  REQUIRE(r.size() == 2);
  CHECK(r[0].event == RtuFramer::Event::bad_crc);
  CHECK(r[1].event == RtuFramer::Event::frame);
  CHECK(r[1].frame == good);
  CHECK_FALSE(f.pending());
}

TEST_CASE("rtu framer: a request cut short and then sent again whole is a frame as it ends") {
  RtuFramer f(1);
  const Bytes good = with_crc({1, 0x03, 0x00, 0x64, 0x00, 0x0A});
  Bytes line(good.begin(), good.begin() + 3);
  line.insert(line.end(), good.begin(), good.end());
  const auto r = feed(f, line, false);
  REQUIRE_FALSE(r.empty());
  CHECK(r.back().event == RtuFramer::Event::frame);
  CHECK(r.back().frame == good);
}

TEST_CASE("rtu framer: another unit's frame whose data holds a whole request for this module or a broadcast is not taken apart") {
  for (const std::uint8_t inner_unit : {std::uint8_t{1}, std::uint8_t{0}}) {
    INFO("inner unit " << int(inner_unit));
    RtuFramer f(1);
    // FC 16 to unit 5 whose data is, byte for byte, a complete FC 06 for the
    // module (or a broadcast one) with its CRC.
    const Bytes inner = with_crc({inner_unit, 0x06, 0x00, 0x10, 0x00, 0x01});
    Bytes body{5, 0x10, 0x00, 0x00, 0x00, 0x04, 0x08};
    body.insert(body.end(), inner.begin(), inner.end());
    const Bytes other = with_crc(body);
    const auto r = feed(f, other, false);
    REQUIRE(r.size() == 1);
    CHECK(r[0].event == RtuFramer::Event::frame);
    CHECK(r[0].frame == other);
  }
}

TEST_CASE("rtu framer: a noise byte before a request does not hide it, nor another unit's traffic after the noise") {
  for (const std::uint8_t noise : {std::uint8_t{0xFF}, std::uint8_t{0xF8}, std::uint8_t{0x00}, std::uint8_t{0x01}}) {
    INFO("noise byte " << int(noise));
    RtuFramer f(1);
    const Bytes good = with_crc({1, 0x03, 0x00, 0x00, 0x00, 0x01});
    Bytes line{noise};
    // Another unit's request and answer on the bus, then ours, with no silence anywhere.
    for (const Bytes& other : {with_crc({5, 0x03, 0x00, 0x00, 0x00, 0x01}), with_crc({5, 0x03, 0x02, 0x12, 0x34})})
      line.insert(line.end(), other.begin(), other.end());
    line.insert(line.end(), good.begin(), good.end());
    const auto r = feed(f, line, false);
    REQUIRE_FALSE(r.empty());
    CHECK(r.back().event == RtuFramer::Event::frame);
    CHECK(r.back().frame == good);
  }
}

TEST_CASE("rtu framer: another unit's request and its answer are frames too, ended by their CRC") {
  RtuFramer f(1);
  const Bytes request = with_crc({5, 0x03, 0x00, 0x00, 0x00, 0x01});
  const Bytes answer = with_crc({5, 0x03, 0x02, 0x12, 0x34});
  Bytes both = request;
  both.insert(both.end(), answer.begin(), answer.end());
  const auto r = feed(f, both);
  REQUIRE(r.size() == 2);
  CHECK(r[0].frame == request);
  CHECK(r[1].frame == answer);
}

TEST_CASE("rtu framer: a frame cut short by silence is a communication error") {
  RtuFramer f(1);
  const auto r = feed(f, {1, 0x03, 0x00, 0x00});
  REQUIRE(r.size() == 1);
  CHECK(r[0].event == RtuFramer::Event::bad_crc);
  CHECK_FALSE(f.pending());
}

TEST_CASE("rtu framer: more than 256 bytes without a frame is an overrun") {
  RtuFramer f(7);
  Bytes noise(300, 0x55);
  noise[0] = 9;  // another unit: ends only where a CRC matches, which never happens here
  const auto r = feed(f, noise);
  REQUIRE_FALSE(r.empty());
  CHECK(r[0].event == RtuFramer::Event::overrun);
}

TEST_CASE("rtu framer: a write for this module longer than 256 bytes is one frame, so that it can be refused with 03") {
  // FC 16 of 124 registers with all their data: 257 bytes with the CRC.
  Bytes body{1, 0x10, 0x00, 0x64, 0x00, 124, 248};
  body.resize(7 + 248, 0);
  const Bytes req = with_crc(body);
  REQUIRE(req.size() == 257);
  RtuFramer f(1);
  const auto r = feed(f, req, false);
  REQUIRE(r.size() == 1);
  CHECK(r[0].event == RtuFramer::Event::frame);
  CHECK(r[0].frame == req);
  // The same bytes for another unit: past 256 bytes an overrun, as before.
  Bytes other = req;
  other[0] = 9;
  RtuFramer g(1);
  const auto s = feed(g, other);
  REQUIRE_FALSE(s.empty());
  CHECK(s[0].event == RtuFramer::Event::overrun);
}
