#include "mbap_stream.hpp"

#include <spdlog/spdlog.h>

#include <array>

namespace server {
namespace {

StreamEnd serve_frames(MbapStream& stream, RequestHandler& handler, const ClientInfo& client) {
  std::array<std::uint8_t, kMbapHeaderSize + 256> frame{};
  const auto header = std::span(frame).first<kMbapHeaderSize>();
  for (;;) {
    if (!stream.next_frame()) return StreamEnd::no_next_frame;
    if (!stream.read(header)) return StreamEnd::closed;
    const MbapHeader h = parse_mbap(header);
    if (!h.valid()) {
      handler.bus_event(client.transport, BusEvent::comm_error);
      spdlog::warn("{}: {}: MBAP protocol {} length {}; closing the connection", client.transport, client.address,
                   h.protocol, h.length);
      return StreamEnd::malformed_header;
    }
    const auto pdu = std::span(frame).subspan(kMbapHeaderSize, h.pdu_size());
    if (!stream.read(pdu)) return StreamEnd::incomplete_frame;
    handler.bus_event(client.transport, BusEvent::message);
    const Reply reply = handler.handle(h.unit, pdu, client);
    if (reply.send && !stream.send(tcp_frame(h.transaction_id, h.unit, reply.pdu))) return StreamEnd::closed;
  }
}

}  // namespace

StreamEnd serve_mbap_stream(MbapStream& stream, RequestHandler& handler, const ClientInfo& client) {
  const StreamEnd end = serve_frames(stream, handler, client);
  handler.disconnected(client);
  return end;
}

}  // namespace server
