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

FrameStep take_frame(const MbapFramer& framer, RequestHandler& handler, const ClientInfo& client) {
  FrameStep step{framer.front(), {}, {}};
  if (step.front == MbapFramer::Front::malformed) {
    const MbapHeader h = framer.header();
    handler.bus_event(client.transport, BusEvent::comm_error);
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
