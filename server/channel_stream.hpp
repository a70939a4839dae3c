#pragma once
// A connection's ByteChannel as the framing loop (server/mbap_stream.hpp)
// reads it: the next frame must begin within the idle timeout, and the whole
// frame, not each of its pieces, must arrive within the frame timeout; a
// reply must leave within the frame timeout too. Plain TCP and TLS run the
// same loop through this.
#include <atomic>
#include <array>
#include <chrono>
#include <cstdint>

#include "byte_channel.hpp"
#include "mbap_stream.hpp"

namespace server {

inline constexpr int kFrameTimeoutMs = 1000;  // the rest of a frame must follow its first byte within this

using Deadline = std::chrono::steady_clock::time_point;

// Waits until fd is readable (or writable); false on the deadline, an error,
// or a stop request.
bool wait_ready(int fd, ChannelIo::Status want, Deadline deadline, const std::atomic<bool>& stop);

class ChannelStream final : public MbapStream {
 public:
  ChannelStream(ByteChannel& channel, int idle_timeout_ms, const std::atomic<bool>& stop)
      : channel_(channel), idle_timeout_ms_(idle_timeout_ms), stop_(stop) {}
  bool next_frame() override;
  bool read(std::span<std::uint8_t> out) override;
  bool send(std::span<const std::uint8_t> frame) override;

 private:
  bool empty() const { return begin_ == end_ && !channel_.buffered(); }

  ByteChannel& channel_;
  int idle_timeout_ms_;
  const std::atomic<bool>& stop_;
  Deadline frame_deadline_{};
  // Buffered reads: one read takes whatever has arrived (usually the whole
  // request), and poll() is called only when nothing is waiting, so a request
  // costs one read instead of two polls and two reads.
  std::array<std::uint8_t, 2048> buf_{};
  std::size_t begin_ = 0, end_ = 0;
};

}  // namespace server
