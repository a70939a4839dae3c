#include "tests/support/raw_tcp.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

namespace test_support {

std::vector<std::uint8_t> raw_tcp_transaction(int port, std::uint8_t unit, const std::vector<std::uint8_t>& pdu,
                                              std::chrono::milliseconds timeout) {
  auto replies = raw_tcp_pipeline(port, {{unit, pdu}}, timeout, 0x1234);
  if (replies.empty()) return {};
  return std::move(replies.front().second);
}

std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>> raw_tcp_pipeline(
    int port, const std::vector<std::pair<std::uint8_t, std::vector<std::uint8_t>>>& requests,
    std::chrono::milliseconds timeout, std::uint16_t first_tid) {
  std::vector<std::pair<std::uint16_t, std::vector<std::uint8_t>>> replies;
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    ::close(fd);
    return replies;
  }
  std::vector<std::uint8_t> frames;
  std::uint16_t tid = first_tid;
  for (const auto& [unit, pdu] : requests) {
    frames.insert(frames.end(), {static_cast<std::uint8_t>(tid >> 8), static_cast<std::uint8_t>(tid & 0xFF), 0, 0,
                                 static_cast<std::uint8_t>((pdu.size() + 1) >> 8),
                                 static_cast<std::uint8_t>((pdu.size() + 1) & 0xFF), unit});
    frames.insert(frames.end(), pdu.begin(), pdu.end());
    ++tid;
  }
  (void)::send(fd, frames.data(), frames.size(), MSG_NOSIGNAL);
  std::vector<std::uint8_t> got;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (replies.size() < requests.size() && std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    std::uint8_t buf[300];
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) break;
    got.insert(got.end(), buf, buf + n);
    // Whole frames off the front: header (7 bytes, length counts unit + PDU), PDU.
    while (got.size() >= 7) {
      const std::size_t length = static_cast<std::size_t>(got[4] << 8 | got[5]);
      if (length < 2 || got.size() < 6 + length) break;
      replies.emplace_back(static_cast<std::uint16_t>(got[0] << 8 | got[1]),
                           std::vector<std::uint8_t>(got.begin() + 7, got.begin() + static_cast<long>(6 + length)));
      got.erase(got.begin(), got.begin() + static_cast<long>(6 + length));
    }
  }
  ::close(fd);
  return replies;
}

}  // namespace test_support
