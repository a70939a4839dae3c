#include "byte_channel.hpp"

#include <sys/socket.h>

#include <cerrno>

namespace server {

using Status = ChannelIo::Status;

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

}  // namespace server
