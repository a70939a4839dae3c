// The floor: a raw TCP ping-pong server that answers each request frame with
// a frame of the size a Modbus server's answer would have (MBAP delimited:
// FC3/FC4 of n registers -> 9 + 2n bytes, FC16 -> 12 bytes, anything else
// echoed), without parsing, validating or storing anything. One thread per
// connection (blocking recv/send), so it can use every core. Its client is
// `modbus_load --raw` (hand-built frames over a plain socket).
//
//   tcp_pingpong --port 1502
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <thread>

#include "bench_util.hpp"

namespace {

void serve(int fd) {
  std::uint8_t in[7 + 256], out[7 + 256]{};
  for (;;) {
    if (!bench::recv_exact(fd, in, 7)) break;
    const std::size_t len = static_cast<std::size_t>((in[4] << 8) | in[5]);
    if (len < 2 || len > 254 || !bench::recv_exact(fd, in + 7, len - 1)) break;
    const std::uint8_t fc = in[7];
    std::size_t pdu = len - 1;  // echo
    if ((fc == 3 || fc == 4) && len >= 6) pdu = 2 + 2 * static_cast<std::size_t>((in[10] << 8) | in[11]);
    else if (fc == 16) pdu = 5;
    pdu = std::min<std::size_t>(pdu, 253);
    std::memcpy(out, in, 7 + std::min(pdu, len - 1));
    out[4] = static_cast<std::uint8_t>((pdu + 1) >> 8);
    out[5] = static_cast<std::uint8_t>((pdu + 1) & 0xFF);
    if (fc == 3 || fc == 4) out[8] = static_cast<std::uint8_t>(pdu - 2);
    const std::size_t n = 7 + pdu;
    if (::send(fd, out, n, MSG_NOSIGNAL) != static_cast<ssize_t>(n)) break;
  }
  ::close(fd);
}

}  // namespace

int main(int argc, char** argv) {
  bench::Args a(argc, argv, {{"host", "127.0.0.1"}, {"port", "1502"}});
  signal(SIGPIPE, SIG_IGN);
  const int s = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const int one = 1;
  ::setsockopt(s, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(a.num("port")));
  ::inet_pton(AF_INET, a.str("host").c_str(), &addr.sin_addr);
  if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) < 0 || ::listen(s, 128) < 0) {
    std::fprintf(stderr, "tcp_pingpong: port %s: %s\n", a.str("port").c_str(), std::strerror(errno));
    return 1;
  }
  std::printf("tcp_pingpong: listening on tcp %s:%s\n", a.str("host").c_str(), a.str("port").c_str());
  std::fflush(stdout);
  for (;;) {
    const int fd = ::accept4(s, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR) continue;
      break;
    }
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    std::thread(serve, fd).detach();
  }
  return 0;
}
