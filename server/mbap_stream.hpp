#pragma once
// The request loop of one Modbus/TCP connection, apart from the socket:
// frames delimited by the MBAP length field as the standard says (libmodbus
// 3.1.6 frames TCP by function code and ignores that length, so one odd
// request would desynchronise the stream), each frame's unit id and PDU handed
// to the RequestHandler, each reply framed back. TcpServer runs it on a
// socket, fuzz/fuzz_tcp_request on a byte buffer: the same loop.
#include <cstdint>
#include <span>

#include "mbap.hpp"
#include "request_handler.hpp"

namespace server {

// The bytes of one connection as the loop reads them.
class MbapStream {
 public:
  virtual ~MbapStream() = default;
  // Waits for the first byte of the next frame; false: there is none (the
  // client closed, stayed idle too long, or the server stops).
  virtual bool next_frame() = 0;
  // The next out.size() bytes of the frame begun; false: the stream ended or
  // the frame took too long.
  virtual bool read(std::span<std::uint8_t> out) = 0;
  // One whole reply frame; false: it could not be sent.
  virtual bool send(std::span<const std::uint8_t> frame) = 0;
};

// Why a connection's loop ended.
enum class StreamEnd {
  no_next_frame,     // next_frame() said so
  closed,            // a header did not arrive whole, or a reply could not be sent
  malformed_header,  // not protocol 0, or a length outside 2..254: the stream cannot be resynchronised
  incomplete_frame,  // the PDU the header announced did not arrive whole
};

// Serves frame after frame until the stream ends, then tells the handler that
// the client left (its jogs stop).
StreamEnd serve_mbap_stream(MbapStream& stream, RequestHandler& handler, const ClientInfo& client);

}  // namespace server
