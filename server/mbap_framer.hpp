#pragma once
// The bytes of one Modbus/TCP connection in, whole frames out, apart from
// any socket: frames delimited by the MBAP length field as the standard says
// (libmodbus 3.1.6 frames TCP by function code and ignores that length, so
// one odd request would desynchronise the stream). The event loop's
// connections (server/tcp_connection.hpp) and fuzz/fuzz_tcp_request feed it
// the same way.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "mbap.hpp"
#include "request_handler.hpp"

namespace server {

class MbapFramer {
 public:
  // Where the next bytes received go (empty: full until the front frame is taken).
  std::span<std::uint8_t> space();
  void received(std::size_t n) { end_ += n; }

  enum class Front : std::uint8_t {
    none,       // no byte of a next frame yet
    partial,    // a frame begun, not whole yet
    frame,      // a whole frame: header() and pdu()
    malformed,  // not protocol 0, or a length outside 2..kLongestMbapLength: the stream cannot be resynchronised
  };
  Front front() const;
  MbapHeader header() const;
  // What a malformed front is when it is another protocol a client mistook
  // for Modbus TCP (a TLS handshake, an HTTP request), said so that the log
  // tells the technician; empty otherwise.
  std::string_view foreign_protocol() const;
  std::span<const std::uint8_t> pdu() const;
  // Drops the whole frame at the front.
  void pop();

 private:
  std::size_t size() const { return end_ - begin_; }

  // Room for several pipelined requests; the largest frame read is 7 + 265 bytes.
  std::array<std::uint8_t, 2048> buf_{};
  std::size_t begin_ = 0, end_ = 0;
};

// What the front of a framer holds for the connection, the bus counters
// (FC 08) counted and a malformed header logged with the client.
struct FrameStep {
  MbapFramer::Front front = MbapFramer::Front::none;
  MbapHeader header;
  std::span<const std::uint8_t> pdu;  // valid until the framer's pop()
};
FrameStep take_frame(const MbapFramer& framer, RequestHandler& handler, const ClientInfo& client);

}  // namespace server
