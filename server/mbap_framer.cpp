#include "mbap_framer.hpp"

#include <spdlog/spdlog.h>

#include <cstring>

namespace server {

std::span<std::uint8_t> MbapFramer::space() {
  if (begin_ > 0 && (end_ == buf_.size() || begin_ == end_)) {  // keep the unread bytes at the front
    std::memmove(buf_.data(), buf_.data() + begin_, size());
    end_ -= begin_;
    begin_ = 0;
  }
  return std::span(buf_).subspan(end_);
}

MbapFramer::Front MbapFramer::front() const {
  if (size() == 0) return Front::none;
  if (size() < kMbapHeaderSize) return Front::partial;
  const MbapHeader h = header();
  if (!h.valid()) return Front::malformed;
  return size() < kMbapHeaderSize + h.pdu_size() ? Front::partial : Front::frame;
}

MbapHeader MbapFramer::header() const {
  return parse_mbap(std::span(buf_).subspan(begin_).first<kMbapHeaderSize>());
}

std::span<const std::uint8_t> MbapFramer::pdu() const {
  return std::span(buf_).subspan(begin_ + kMbapHeaderSize, header().pdu_size());
}

void MbapFramer::pop() { begin_ += kMbapHeaderSize + header().pdu_size(); }

std::string_view MbapFramer::foreign_protocol() const {
  if (size() < 4) return {};
  const std::uint8_t* b = buf_.data() + begin_;
  // A TLS record of type handshake, version 3.x, holding a ClientHello (type 1).
  if (size() >= 6 && b[0] == 0x16 && b[1] == 0x03 && b[2] <= 0x04 && b[5] == 0x01)
    return "a TLS handshake: this port serves plain Modbus TCP; a Modbus/TCP Security client connects to the "
           "module's --tls port";
  static constexpr std::string_view kHttp[] = {"GET ", "POST", "HEAD", "PUT ", "OPTI", "CONN"};
  if (size() >= 4)
    for (std::string_view m : kHttp)
      if (std::memcmp(b, m.data(), 4) == 0) return "an HTTP request: the module speaks Modbus TCP, not HTTP";
  return {};
}

FrameStep take_frame(const MbapFramer& framer, RequestHandler& handler, const ClientInfo& client) {
  FrameStep step{framer.front(), {}, {}};
  if (step.front == MbapFramer::Front::malformed) {
    const MbapHeader h = framer.header();
    handler.bus_event(client.transport, BusEvent::comm_error);
    if (const std::string_view foreign = framer.foreign_protocol(); !foreign.empty())
      spdlog::warn("{}: {}: not Modbus but {}; closing the connection", client.transport, client.address, foreign);
    else
      spdlog::warn("{}: {}: MBAP protocol {} length {}; closing the connection", client.transport, client.address,
                   h.protocol, h.length);
  } else if (step.front == MbapFramer::Front::frame) {
    handler.bus_event(client.transport, BusEvent::message);
    step.header = framer.header();
    step.pdu = framer.pdu();
  }
  return step;
}

}  // namespace server
