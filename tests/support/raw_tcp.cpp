#include "tests/support/raw_tcp.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

namespace test_support {

std::vector<std::uint8_t> raw_tcp_transaction(int port, std::uint8_t unit, const std::vector<std::uint8_t>& pdu,
                                              std::chrono::milliseconds timeout) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    ::close(fd);
    return {};
  }
  std::vector<std::uint8_t> frame{0x12, 0x34, 0, 0, static_cast<std::uint8_t>((pdu.size() + 1) >> 8),
                                  static_cast<std::uint8_t>((pdu.size() + 1) & 0xFF), unit};
  frame.insert(frame.end(), pdu.begin(), pdu.end());
  (void)::send(fd, frame.data(), frame.size(), MSG_NOSIGNAL);
  std::vector<std::uint8_t> got;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::size_t want = 7;
  while (got.size() < want && std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    std::uint8_t buf[300];
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) break;
    got.insert(got.end(), buf, buf + n);
    if (got.size() >= 6) want = 6 + ((got[4] << 8) | got[5]);
  }
  ::close(fd);
  if (got.size() < want || got.size() < 8) return {};
  return std::vector<std::uint8_t>(got.begin() + 7, got.begin() + static_cast<long>(want));
}

}  // namespace test_support
