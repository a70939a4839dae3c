#include "channel_stream.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace server {

using Status = ChannelIo::Status;
using Clock = std::chrono::steady_clock;

ChannelIo SocketChannel::read(std::span<std::uint8_t> out) {
  for (;;) {
    const ssize_t r = ::recv(fd_, out.data(), out.size(), MSG_DONTWAIT);
    if (r > 0) return {Status::done, static_cast<std::size_t>(r)};
    if (r == 0) return {Status::closed};
    if (errno == EINTR) continue;
    return {errno == EAGAIN || errno == EWOULDBLOCK ? Status::want_read : Status::closed};
  }
}

ChannelIo SocketChannel::write(std::span<const std::uint8_t> bytes) {
  for (;;) {
    const ssize_t r = ::send(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    if (r >= 0) return {Status::done, static_cast<std::size_t>(r)};
    if (errno == EINTR) continue;
    return {errno == EAGAIN || errno == EWOULDBLOCK ? Status::want_write : Status::closed};
  }
}

bool wait_ready(int fd, Status want, Deadline deadline, const std::atomic<bool>& stop) {
  const short events = want == Status::want_write ? POLLOUT : POLLIN;
  while (!stop) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) return false;
    pollfd p{fd, events, 0};
    const int rc = ::poll(&p, 1, static_cast<int>(std::min<long long>(200, left)));  // slices: see stop soon
    if (rc > 0) return true;
    if (rc < 0 && errno != EINTR) return false;
  }
  return false;
}

bool ChannelStream::next_frame() {
  if (empty() &&
      !wait_ready(channel_.fd(), Status::want_read, Clock::now() + std::chrono::milliseconds(idle_timeout_ms_), stop_))
    return false;
  frame_deadline_ = Clock::now() + std::chrono::milliseconds(kFrameTimeoutMs);
  return true;
}

bool ChannelStream::read(std::span<std::uint8_t> out) {
  while (end_ - begin_ < out.size()) {
    if (begin_ > 0) {  // keep the unread bytes at the front
      std::memmove(buf_.data(), buf_.data() + begin_, end_ - begin_);
      end_ -= begin_;
      begin_ = 0;
    }
    const ChannelIo io = channel_.read(std::span(buf_).subspan(end_));
    if (io.status == Status::done) {
      end_ += io.bytes;
      continue;
    }
    if (io.status == Status::closed || !wait_ready(channel_.fd(), io.status, frame_deadline_, stop_)) return false;
  }
  std::memcpy(out.data(), buf_.data() + begin_, out.size());
  begin_ += out.size();
  return true;
}

bool ChannelStream::send(std::span<const std::uint8_t> frame) {
  const Deadline deadline = Clock::now() + std::chrono::milliseconds(kFrameTimeoutMs);
  while (!frame.empty()) {
    const ChannelIo io = channel_.write(frame);
    if (io.status == Status::done) {
      frame = frame.subspan(io.bytes);
      continue;
    }
    if (io.status == Status::closed || !wait_ready(channel_.fd(), io.status, deadline, stop_)) return false;
  }
  return true;
}

}  // namespace server
