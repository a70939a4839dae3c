// Modbus/TCP Security beside plain Modbus TCP, measured with one client
// implementation for both (MBAP frames built here; TLS through tls::Client,
// plain TCP on a socket), so that the difference is TLS alone.
//
//   tls_load --port P --clients N --duration S                        plain TCP load
//   tls_load --port P --tls --pki DIR --clients N --duration S        the same over TLS
//   tls_load --port P [--tls --pki DIR] --connects N                  connection cost
//
// Load: each client repeats FC3 of 10 holding registers at --read-addr (unit
// --unit), one request in flight. Connection cost: N times one after the
// other, connect (and handshake), one FC3 of 10 registers, close; the time to
// the established connection and to the first answer. TLS clients show
// DIR/<--cert>.crt (default engineer) and check the module against DIR/ca.crt
// (the certificates of tools/tls/make-certs.sh).
//
// Prints a readable line, then "RESULT key=value ..." for scripts.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <thread>

#include "bench_util.hpp"
#include "tls/client.hpp"
#include "tls/context.hpp"

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kTimeout = std::chrono::seconds(2);

struct Config {
  int port = 0, clients = 1, read_addr = 100, unit = 1;
  long connects = 0;
  double duration_s = 2;
  bool tls = false;
  std::string pki, cert;
};

// One connection, plain or TLS, that sends a frame and reads bytes.
class Link {
 public:
  virtual ~Link() = default;
  virtual bool send(std::span<const std::uint8_t> bytes) = 0;
  virtual bool read_exact(std::span<std::uint8_t> out) = 0;
};

class PlainLink final : public Link {
 public:
  explicit PlainLink(int fd) : fd_(fd) {}
  ~PlainLink() override { ::close(fd_); }
  bool send(std::span<const std::uint8_t> b) override {
    return ::send(fd_, b.data(), b.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(b.size());
  }
  bool read_exact(std::span<std::uint8_t> out) override {
    std::size_t got = 0;
    while (got < out.size()) {
      const ssize_t r = ::recv(fd_, out.data() + got, out.size() - got, 0);
      if (r <= 0) return false;
      got += static_cast<std::size_t>(r);
    }
    return true;
  }

 private:
  int fd_;
};

class TlsLink final : public Link {
 public:
  explicit TlsLink(tls::Client client) : client_(std::move(client)) {}
  // "TLSv1.3/TLS_AES_256_GCM_SHA384": what was agreed.
  std::string agreed() const {
    const SSL* ssl = client_.session().ssl();
    return std::string(SSL_get_version(ssl)) + "/" + SSL_get_cipher_name(ssl);
  }
  bool send(std::span<const std::uint8_t> b) override { return client_.write_all(b, Clock::now() + kTimeout).has_value(); }
  bool read_exact(std::span<std::uint8_t> out) override {
    return client_.read_exact(out, Clock::now() + kTimeout).has_value();
  }

 private:
  tls::Client client_;
};

// The protocol and cipher suite of a TLS connection ("-" for plain TCP), as
// the first connection agreed them.
std::string g_agreed = "-";
std::once_flag g_agreed_once;

std::unique_ptr<Link> connect(const Config& c, SSL_CTX* ctx) {
  if (c.tls) {
    auto client = tls::Client::connect("127.0.0.1", c.port, ctx, kTimeout);
    if (!client) {
      std::fprintf(stderr, "tls_load: %s\n", client.error().c_str());
      return nullptr;
    }
    auto link = std::make_unique<TlsLink>(std::move(*client));
    std::call_once(g_agreed_once, [&] { g_agreed = link->agreed(); });
    return link;
  }
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(c.port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    if (fd >= 0) ::close(fd);
    return nullptr;
  }
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  timeval tv{2, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  return std::make_unique<PlainLink>(fd);
}

// FC3 of 10 registers; true when a well-framed, non-exception answer came.
bool read10(Link& link, const Config& c, std::uint16_t tid) {
  const std::uint8_t req[] = {static_cast<std::uint8_t>(tid >> 8), static_cast<std::uint8_t>(tid), 0, 0, 0, 6,
                              static_cast<std::uint8_t>(c.unit), 3, static_cast<std::uint8_t>(c.read_addr >> 8),
                              static_cast<std::uint8_t>(c.read_addr), 0, 10};
  std::uint8_t reply[7 + 2 + 20];
  if (!link.send(req) || !link.read_exact(std::span(reply).first(7))) return false;
  const std::size_t len = static_cast<std::size_t>((reply[4] << 8) | reply[5]);
  if (len != 2 + 20 + 1) return false;  // an exception or a wrong size
  return link.read_exact(std::span(reply).subspan(7, len - 1)) && ((reply[0] << 8) | reply[1]) == tid;
}

struct Sample {
  std::vector<double> latency_us;
  std::uint64_t errors = 0;
};

void print_latency(const char* what, std::vector<double>& v, double per_s, std::uint64_t errors) {
  const double p50 = bench::percentile(v, 0.5), p99 = bench::percentile(v, 0.99),
               p999 = bench::percentile(v, 0.999), mx = v.empty() ? 0 : *std::max_element(v.begin(), v.end());
  std::printf("%s: %.0f/s, p50 %.1f us, p99 %.1f us, p99.9 %.1f us, max %.1f us, %llu errors\n", what, per_s, p50, p99,
              p999, mx, (unsigned long long)errors);
}

int load(const Config& c, SSL_CTX* ctx) {
  std::vector<Sample> samples(static_cast<std::size_t>(c.clients));
  std::atomic<bool> go{false};
  std::atomic<std::int64_t> end_ns{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < c.clients; ++i) {
    threads.emplace_back([&, i] {
      Sample& s = samples[static_cast<std::size_t>(i)];
      auto link = connect(c, ctx);
      s.latency_us.reserve(1 << 16);
      while (!go) std::this_thread::yield();
      for (std::uint16_t tid = 1;; ++tid) {
        const std::int64_t t0 = bench::now_ns();
        if (t0 >= end_ns) break;
        if (!link) {
          ++s.errors;
          std::this_thread::sleep_for(std::chrono::milliseconds(10));
          link = connect(c, ctx);
          continue;
        }
        if (read10(*link, c, tid)) {
          s.latency_us.push_back(static_cast<double>(bench::now_ns() - t0) / 1000.0);
        } else {
          ++s.errors;
          link.reset();
        }
      }
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50 + 5 * c.clients));  // every client connected
  const std::int64_t start = bench::now_ns();
  end_ns = start + static_cast<std::int64_t>(c.duration_s * 1e9);
  go = true;
  for (auto& t : threads) t.join();
  const double seconds = static_cast<double>(bench::now_ns() - start) / 1e9;
  std::vector<double> all;
  std::uint64_t errors = 0;
  for (auto& s : samples) {
    all.insert(all.end(), s.latency_us.begin(), s.latency_us.end());
    errors += s.errors;
  }
  const double rps = static_cast<double>(all.size()) / seconds;
  const std::string what = std::string(c.tls ? "tls" : "tcp") + ", " + std::to_string(c.clients) + " clients";
  print_latency(what.c_str(), all, rps, errors);
  std::printf("RESULT transport=%s agreed=%s clients=%d seconds=%.3f requests=%zu rps=%.1f p50_us=%.1f p99_us=%.1f "
              "p999_us=%.1f max_us=%.1f errors=%llu\n",
              c.tls ? "tls" : "tcp", g_agreed.c_str(), c.clients, seconds, all.size(), rps, bench::percentile(all, 0.5),
              bench::percentile(all, 0.99), bench::percentile(all, 0.999),
              all.empty() ? 0.0 : *std::max_element(all.begin(), all.end()), (unsigned long long)errors);
  return errors == 0 ? 0 : 1;
}

int connects(const Config& c, SSL_CTX* ctx) {
  std::vector<double> established_us, answered_us;
  std::uint64_t errors = 0;
  const std::int64_t start = bench::now_ns();
  for (long i = 0; i < c.connects; ++i) {
    const std::int64_t t0 = bench::now_ns();
    auto link = connect(c, ctx);
    const std::int64_t t1 = bench::now_ns();
    if (!link || !read10(*link, c, 1)) {
      ++errors;
      continue;
    }
    established_us.push_back(static_cast<double>(t1 - t0) / 1000.0);
    answered_us.push_back(static_cast<double>(bench::now_ns() - t0) / 1000.0);
  }
  const double seconds = static_cast<double>(bench::now_ns() - start) / 1e9;
  const double per_s = static_cast<double>(answered_us.size()) / seconds;
  std::printf("%s connections: %.0f/s\n", c.tls ? "tls" : "tcp", per_s);
  print_latency("  connected (TLS: handshake done)", established_us, per_s, errors);
  print_latency("  first answer", answered_us, per_s, errors);
  std::printf("RESULT transport=%s agreed=%s connects=%zu per_s=%.1f connect_p50_us=%.1f connect_p99_us=%.1f "
              "answer_p50_us=%.1f answer_p99_us=%.1f errors=%llu\n",
              c.tls ? "tls" : "tcp", g_agreed.c_str(), answered_us.size(), per_s, bench::percentile(established_us, 0.5),
              bench::percentile(established_us, 0.99), bench::percentile(answered_us, 0.5),
              bench::percentile(answered_us, 0.99), (unsigned long long)errors);
  return errors == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  bench::Args a(argc, argv,
                {{"port", "802"}, {"clients", "1"}, {"duration", "2"}, {"read-addr", "100"}, {"unit", "1"},
                 {"connects", "0"}, {"tls", "false"}, {"pki", ""}, {"cert", "engineer"}});
  Config c;
  c.port = static_cast<int>(a.num("port"));
  c.clients = static_cast<int>(a.num("clients"));
  c.duration_s = a.real("duration");
  c.read_addr = static_cast<int>(a.num("read-addr"));
  c.unit = static_cast<int>(a.num("unit"));
  c.connects = a.num("connects");
  c.tls = a.flag("tls");
  c.pki = a.str("pki");
  c.cert = a.str("cert");
  tls::SslCtx ctx;
  if (c.tls) {
    if (c.pki.empty()) {
      std::fprintf(stderr, "tls_load: --tls needs --pki DIR (tools/tls/make-certs.sh init DIR)\n");
      return 2;
    }
    auto made = tls::client_context({c.pki + "/" + c.cert + ".crt", c.pki + "/" + c.cert + ".key", c.pki + "/ca.crt"});
    if (!made) {
      std::fprintf(stderr, "tls_load: %s\n", made.error().c_str());
      return 2;
    }
    ctx = std::move(*made);
  }
  return c.connects > 0 ? connects(c, ctx.get()) : load(c, ctx.get());
}
