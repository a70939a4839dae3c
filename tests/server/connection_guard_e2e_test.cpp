// Connections one client cannot hog, against the real homingd: one address
// (127.0.0.2) holds every connection and keeps polling, yet the privileged HMI
// (127.0.0.3, --privileged) and an ordinary client (127.0.0.4) are served: the
// least recently active connection of the hog is closed to make room, logged
// with both addresses. The clients bind other loopback addresses (the whole
// 127.0.0.0/8 is loopback on Linux); homingd listens on 127.0.0.1 only.
#include <arpa/inet.h>
#include <catch2/catch.hpp>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <memory>

#include "daemon.hpp"
#include "tests/support/test_pki.hpp"
#include "tests/support/tls_modbus_client.hpp"

using namespace e2e;

namespace {

// A Modbus/TCP connection from a chosen loopback source address.
class From {
 public:
  From(const char* source, int port) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in src{};
    src.sin_family = AF_INET;
    ::inet_pton(AF_INET, source, &src.sin_addr);
    sockaddr_in dst{};
    dst.sin_family = AF_INET;
    dst.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    dst.sin_port = htons(static_cast<std::uint16_t>(port));
    connected_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&src), sizeof(src)) == 0 &&
                 ::connect(fd_, reinterpret_cast<sockaddr*>(&dst), sizeof(dst)) == 0;
    sockaddr_in local{};
    socklen_t len = sizeof(local);
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&local), &len);
    name_ = std::string(source) + ":" + std::to_string(ntohs(local.sin_port));
  }
  ~From() { ::close(fd_); }
  From(const From&) = delete;
  From& operator=(const From&) = delete;

  bool connected() const { return connected_; }
  const std::string& name() const { return name_; }

  // Reads status.map_version (FC 04): true when the module answered it.
  bool served(std::chrono::milliseconds timeout = 3000ms) {
    ++tid_;
    const std::uint8_t req[] = {static_cast<std::uint8_t>(tid_ >> 8), static_cast<std::uint8_t>(tid_), 0, 0, 0, 6, 1,
                                4, 0, 0, 0, 1};
    if (::send(fd_, req, sizeof(req), MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof(req))) return false;
    std::vector<std::uint8_t> got;
    const auto deadline = Clock::now() + timeout;
    while (got.size() < 11 && Clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      std::uint8_t buf[64];
      const ssize_t n = ::recv(fd_, buf, sizeof(buf), 0);
      if (n <= 0) return false;
      got.insert(got.end(), buf, buf + n);
    }
    return got.size() == 11 && got[0] == (tid_ >> 8) && got[1] == (tid_ & 0xFF) && got[7] == 4;
  }
  // True when the server closed the connection within the timeout.
  bool closed_within(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      std::uint8_t buf[64];
      const ssize_t n = ::recv(fd_, buf, sizeof(buf), MSG_DONTWAIT);
      if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) return true;
    }
    return false;
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
  std::uint16_t tid_ = 0;
  std::string name_;
};

bool log_has(const Daemon& d, const std::string& what) {
  return wait_until([&] { return d.log().find(what) != std::string::npos; }, 5s);
}

}  // namespace

TEST_CASE("one address holding every connection does not lock out the privileged HMI nor an ordinary client") {
  constexpr int kMax = 8;
  Daemon d({.extra = {"--max-clients", std::to_string(kMax), "--privileged", "127.0.0.3"}});
  // The hog takes every connection, each polled once, in order: the first is
  // the least recently active.
  std::vector<std::unique_ptr<From>> hog;
  for (int i = 0; i < kMax; ++i) {
    hog.push_back(std::make_unique<From>("127.0.0.2", d.port()));
    REQUIRE(hog.back()->connected());
    REQUIRE(hog.back()->served());
  }
  // Full: the hog's next one is refused (its own do not give way to it).
  {
    From more("127.0.0.2", d.port());
    CHECK_FALSE(more.served(2000ms));
  }

  // The HMI gets in: the hog's least recently active connection is closed for it.
  From hmi("127.0.0.3", d.port());
  REQUIRE(hmi.connected());
  CHECK(hmi.served());
  CHECK(hog[0]->closed_within(3000ms));
  CHECK(log_has(d, "closed " + hog[0]->name() + " (the least recently active"));
  CHECK(log_has(d, "to make room for " + hmi.name() + " (privileged)"));

  // The hog keeps polling the rest; an ordinary client still gets in, and
  // the connection closed for it is the hog's, not the HMI's (which is idle now).
  for (int i = 2; i < kMax; ++i) CHECK(hog[i]->served());
  From client("127.0.0.4", d.port());
  REQUIRE(client.connected());
  CHECK(client.served());
  CHECK(hog[1]->closed_within(3000ms));
  CHECK(log_has(d, "closed " + hog[1]->name() + " (the least recently active"));
  CHECK(log_has(d, "to make room for " + client.name() + ":"));
  CHECK(hmi.served());
  for (int i = 2; i < kMax; ++i) CHECK(hog[i]->served());

  // Another client of another address: again one of the hog's gives way, never the HMI.
  From other("127.0.0.5", d.port());
  CHECK(other.served());
  CHECK(hog[2]->closed_within(3000ms));
  CHECK(hmi.served());
  CHECK(client.served());
}

TEST_CASE("an address at --max-clients-per-address is refused its next connection while others are served") {
  Daemon d({.extra = {"--max-clients-per-address", "2"}});
  From a("127.0.0.2", d.port());
  From b("127.0.0.2", d.port());
  REQUIRE(a.served());
  REQUIRE(b.served());
  From third("127.0.0.2", d.port());
  CHECK_FALSE(third.served(2000ms));
  CHECK(third.closed_within(2000ms));
  CHECK(log_has(d, "refused " + third.name() + ": 127.0.0.2 holds 2 connections, the maximum per address "
                   "(--max-clients-per-address)"));
  From other("127.0.0.4", d.port());
  CHECK(other.served());
  CHECK(a.served());
  CHECK(b.served());
}

TEST_CASE("homingd refuses a --privileged entry that is not an IPv4 address or CIDR") {
  const RunResult r = run_program({homingd_path(), "--privileged", "plc.local"}, 10s);
  REQUIRE(r.exited());
  CHECK(r.code() != 0);
  CHECK(r.err.find("--privileged: 'plc.local' is not an IPv4 address or CIDR") != std::string::npos);
}

TEST_CASE("the TLS listener shares its connections the same way: a hog's connections give way to a privileged engineer") {
  DaemonOptions options;
  options.tls = tls_server_options();
  options.extra = {"--max-clients", "2", "--privileged", "127.0.0.1"};
  Daemon d(std::move(options));
  // The hog holds both TLS connections, stalled before its handshake. It
  // would lose them at the handshake timeout (3 s) anyway: the log line
  // proves they were closed for the engineer; tried again if they were not.
  bool made_room = false;
  for (int attempt = 0; attempt < 5 && !made_room; ++attempt) {
    From a("127.0.0.2", d.tls_port());
    From b("127.0.0.2", d.tls_port());
    REQUIRE(a.connected());
    REQUIRE(b.connected());
    auto engineer = TlsModbusClient::connect(d.tls_port(), tls_identity("engineer"));
    REQUIRE(engineer);
    CHECK(engineer->read("status.map_version") == registers::kMapVersion);
    made_room = wait_until(
        [&] {
          const std::string log = d.log();
          return log.find("tls: closed " + a.name() + " (the least recently active") != std::string::npos &&
                 log.find("to make room for 127.0.0.1:") != std::string::npos;
        },
        2s);
  }
  CHECK(made_room);
}
