// Modbus load generator: N client connections for a bounded time, one request
// mix, and the figures that matter: requests per second, latency percentiles,
// errors.
//
//   modbus_load --port 1502 --clients 8 --duration 3 --mix mixed [--home]
//
// Mixes (each client repeats its mix back to back, one request in flight):
//   read10    FC3, 10 holding registers at --read-addr (unit --unit)
//   read125   FC3, 125 holding registers at --read-addr
//   write10   FC16, 10 holding registers at --write-addr (unit --write-unit),
//             writing back the values read there at connect (no state change)
//   mixed     read10, read125, read10, write10 (3 reads : 1 write)
//   production  what an HMI, a PLC and a SCADA poller send, in one poll cycle:
//             FC4 status block (input 0-17), FC4 axis X block (input 100-153),
//             FC2 discrete inputs (0-2), FC1 command coils (0-4), FC6 the host
//             heartbeat (holding 20, a counter), FC4 status block again, FC3
//             axis X settings (holding 100-139), FC5 cmd.reset_alarm (coil 2):
//             no simulator writes, no settings writes
//   durable   FC16, 10 registers at --durable-addr (unit --unit), one client
//             word toggling between two values so every write changes a
//             setting (homingd commits it to SQLite before answering); with
//             several clients each writes its own settings (client i: the
//             axis block i % 6 above --durable-addr, word 7, 5 or 3), so that
//             no write finds its value already there
// --pause-ms N: each client waits N ms after each answer (not counted), so a
// daemon idles between requests: write10 then times a simulator write that
// must wake its control loop (bench/run_benchmarks.py, idle).
// Transports: libmodbus TCP (default), --raw (hand-built MBAP frames over a
// plain socket: the client side of the TCP ping-pong floor), --rtu DEVICE.
// --home: a side connection (not counted) reads status.state (input register
// 1) every 5 ms and writes cmd.home_all (coil 0) whenever no cycle runs, so
// homingd homes on its simulator during the load.
//
// --sync: for run_benchmarks.py, which reads the server's /proc counters at the
// edges of the measured stretch: once the clients are connected it prints
// "WINDOW ready" and starts them only when a line arrives on stdin; once every
// client is done, before any closes its connection (a server thread per
// connection is still there to be read), it prints "WINDOW end" and closes
// when the next line arrives. Both reads thus happen while the clients are
// idle: a reader starved of CPU by the load itself is late without cutting
// the stretch short.
//
// Prints one line "RESULT key=value ..." (for scripts) after a readable one,
// with the load generator's own CPU and context switches over the stretch
// (bench::SelfCounters), so the load's cost to the shared cores is known.
// Then "PER_CLIENT" (requests per client: min, p10, p50, p90, max; how evenly
// the server served them; RESULT's client_spread is p10 / p90) and, for mixes of several requests, "BY_REQUEST"
// (count, p50 and p99 of each kind).
#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

#include "bench_util.hpp"

namespace {

enum class Op { read10, read125, write10, durable, status, axis_inputs, discretes, coils, heartbeat, axis_settings, command };

struct Config {
  std::string host, rtu, mix;
  int port = 1502, clients = 1, unit = 1, write_unit = 247, read_addr = 100, write_addr = 102, durable_addr = 120;
  int baud = 19200;
  char parity = 'E';
  double duration_s = 3;
  long max_requests = 0;
  int pause_ms = 0;
  bool raw = false, home = false;
  std::vector<Op> ops;
};

struct ClientResult {
  std::vector<double> latency_us;
  std::vector<Op> latency_op;  // the request each latency belongs to
  std::uint64_t ok = 0, exceptions = 0, exc06 = 0, transport_errors = 0, reconnects = 0;
  bool connected = false;
};

// --- raw MBAP over a socket ----------------------------------------------------

int raw_connect(const Config& c) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(c.port));
  ::inet_pton(AF_INET, c.host.c_str(), &a.sin_addr);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) < 0) {
    ::close(fd);
    return -1;
  }
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  timeval tv{2, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  return fd;
}

// One raw request; returns 0 ok, >0 exception code, -1 transport error.
int raw_request(int fd, std::uint16_t tid, std::uint8_t unit, const std::vector<std::uint8_t>& pdu) {
  std::uint8_t out[7 + 256];
  out[0] = tid >> 8;
  out[1] = tid & 0xFF;
  out[2] = out[3] = 0;
  out[4] = static_cast<std::uint8_t>((pdu.size() + 1) >> 8);
  out[5] = static_cast<std::uint8_t>((pdu.size() + 1) & 0xFF);
  out[6] = unit;
  std::memcpy(out + 7, pdu.data(), pdu.size());
  const std::size_t n = 7 + pdu.size();
  if (::send(fd, out, n, MSG_NOSIGNAL) != static_cast<ssize_t>(n)) return -1;
  std::uint8_t in[7 + 256];
  if (!bench::recv_exact(fd, in, 7)) return -1;
  const std::size_t len = static_cast<std::size_t>((in[4] << 8) | in[5]);
  if (len < 2 || len > 254 || !bench::recv_exact(fd, in + 7, len - 1)) return -1;
  if (((in[0] << 8) | in[1]) != tid) return -1;
  if (in[7] & 0x80) return len >= 3 ? in[8] : 1;
  return 0;
}

std::vector<std::uint8_t> raw_pdu(Op op, const Config& c, const std::uint16_t* words, int count, int durable_addr) {
  std::vector<std::uint8_t> p;
  auto put16 = [&](int v) {
    p.push_back(static_cast<std::uint8_t>(v >> 8));
    p.push_back(static_cast<std::uint8_t>(v & 0xFF));
  };
  switch (op) {
    case Op::status: p = {4}; put16(0); put16(18); return p;
    case Op::axis_inputs: p = {4}; put16(100); put16(54); return p;
    case Op::discretes: p = {2}; put16(0); put16(3); return p;
    case Op::coils: p = {1}; put16(0); put16(5); return p;
    case Op::heartbeat: p = {6}; put16(20); put16(words[0]); return p;
    case Op::axis_settings: p = {3}; put16(100); put16(40); return p;
    case Op::command: p = {5}; put16(2); put16(0xFF00); return p;
    default: break;
  }
  if (op == Op::read10 || op == Op::read125) {
    p.push_back(3);
    put16(c.read_addr);
    put16(op == Op::read10 ? 10 : 125);
  } else {
    p.push_back(16);
    put16(op == Op::durable ? durable_addr : c.write_addr);
    put16(count);
    p.push_back(static_cast<std::uint8_t>(count * 2));
    for (int i = 0; i < count; ++i) put16(words[i]);
  }
  return p;
}

// --- libmodbus -----------------------------------------------------------------

modbus_t* mb_connect(const Config& c) {
  modbus_t* ctx = c.rtu.empty() ? modbus_new_tcp(c.host.c_str(), c.port)
                                : modbus_new_rtu(c.rtu.c_str(), c.baud, c.parity, 8, 1);
  if (!ctx) return nullptr;
  modbus_set_response_timeout(ctx, 2, 0);
  modbus_set_slave(ctx, c.unit);
  if (modbus_connect(ctx) < 0) {
    modbus_free(ctx);
    return nullptr;
  }
  return ctx;
}

int exception_of(int err) {
  if (err > MODBUS_ENOBASE && err < MODBUS_ENOBASE + 12) return err - MODBUS_ENOBASE;
  return -1;
}

// --sync: clients that are done wait here, connected, until released.
struct Hold {
  std::mutex m;
  std::condition_variable cv;
  int arrived = 0;
  bool released = false;
  void arrive_and_wait() {
    std::unique_lock lock(m);
    ++arrived;
    cv.notify_all();
    cv.wait(lock, [this] { return released; });
  }
  void wait_for(int n) {
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return arrived >= n; });
  }
  void release() {
    std::lock_guard lock(m);
    released = true;
    cv.notify_all();
  }
};

void run_client(const Config& c, int index, ClientResult& r, const std::atomic<bool>& go,
                const std::atomic<std::int64_t>& deadline_ns, Hold* hold) {
  const int durable_addr = c.durable_addr + 100 * (index % 6);
  const int durable_word = 7 - 2 * ((index / 6) % 3);
  modbus_t* ctx = nullptr;
  int fd = -1;
  auto connect = [&] {
    if (c.raw) fd = raw_connect(c);
    else ctx = mb_connect(c);
    return c.raw ? fd >= 0 : ctx != nullptr;
  };
  auto disconnect = [&] {
    if (ctx) {
      modbus_close(ctx);
      modbus_free(ctx);
      ctx = nullptr;
    }
    if (fd >= 0) ::close(fd);
    fd = -1;
  };
  r.connected = connect();
  // The values written back by write10 (read once at connect), and the two
  // alternating value sets of the durable mix.
  std::uint16_t write_words[10]{}, durable_words[10]{};
  auto uses = [&](Op op) { return std::find(c.ops.begin(), c.ops.end(), op) != c.ops.end(); };
  if (r.connected && !c.raw && uses(Op::write10)) {
    modbus_set_slave(ctx, c.write_unit);
    if (modbus_read_registers(ctx, c.write_addr, 10, write_words) != 10) std::memset(write_words, 0, sizeof(write_words));
    modbus_set_slave(ctx, c.unit);
  }
  if (r.connected && !c.raw && uses(Op::durable) &&
      modbus_read_registers(ctx, durable_addr, 10, durable_words) != 10)
    std::memset(durable_words, 0, sizeof(durable_words));
  r.latency_us.reserve(1 << 16);
  r.latency_op.reserve(1 << 16);
  while (!go) std::this_thread::yield();
  std::uint16_t tid = 0;
  std::uint16_t values[125];
  std::uint8_t bits[8];
  std::uint16_t heartbeat = 0;
  long done = 0;
  for (std::size_t i = 0;; ++i) {
    if (c.max_requests > 0 && done >= c.max_requests) break;
    const std::int64_t t0 = bench::now_ns();
    if (t0 >= deadline_ns) break;
    if (!r.connected) {
      r.connected = connect();
      ++r.reconnects;
      if (!r.connected) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
    }
    const Op op = c.ops[i % c.ops.size()];
    if (op == Op::durable) durable_words[durable_word] ^= 1;
    if (op == Op::heartbeat) ++heartbeat;
    int outcome = 0;
    if (c.raw) {
      const bool w = op == Op::write10 || op == Op::durable;
      const std::uint16_t* words = op == Op::durable ? durable_words : op == Op::heartbeat ? &heartbeat : write_words;
      const auto pdu = raw_pdu(op, c, words, w ? 10 : 0, durable_addr);
      outcome = raw_request(fd, ++tid, static_cast<std::uint8_t>(op == Op::write10 ? c.write_unit : c.unit), pdu);
    } else {
      int rc = -1;
      switch (op) {
        case Op::read10: rc = modbus_read_registers(ctx, c.read_addr, 10, values); break;
        case Op::read125: rc = modbus_read_registers(ctx, c.read_addr, 125, values); break;
        case Op::write10:
          modbus_set_slave(ctx, c.write_unit);
          rc = modbus_write_registers(ctx, c.write_addr, 10, write_words);
          modbus_set_slave(ctx, c.unit);
          break;
        case Op::durable: rc = modbus_write_registers(ctx, durable_addr, 10, durable_words); break;
        case Op::status: rc = modbus_read_input_registers(ctx, 0, 18, values); break;
        case Op::axis_inputs: rc = modbus_read_input_registers(ctx, 100, 54, values); break;
        case Op::discretes: rc = modbus_read_input_bits(ctx, 0, 3, bits); break;
        case Op::coils: rc = modbus_read_bits(ctx, 0, 5, bits); break;
        case Op::heartbeat: rc = modbus_write_register(ctx, 20, heartbeat); break;
        case Op::axis_settings: rc = modbus_read_registers(ctx, 100, 40, values); break;
        case Op::command: rc = modbus_write_bit(ctx, 2, 1); break;
      }
      outcome = rc >= 0 ? 0 : exception_of(errno);
    }
    const std::int64_t t1 = bench::now_ns();
    ++done;
    if (outcome == 0) {
      ++r.ok;
      r.latency_us.push_back((t1 - t0) / 1000.0);
      r.latency_op.push_back(op);
    } else if (outcome > 0) {
      ++r.exceptions;
      if (outcome == 6) ++r.exc06;
      r.latency_us.push_back((t1 - t0) / 1000.0);
      r.latency_op.push_back(op);
    } else {
      ++r.transport_errors;
      disconnect();
      r.connected = false;
    }
    if (c.pause_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(c.pause_ms));
  }
  if (hold) hold->arrive_and_wait();
  disconnect();
}

const char* op_name(Op op) {
  switch (op) {
    case Op::read10: return "read10";
    case Op::read125: return "read125";
    case Op::write10: return "write10";
    case Op::durable: return "durable";
    case Op::status: return "status";
    case Op::axis_inputs: return "axis_inputs";
    case Op::discretes: return "discretes";
    case Op::coils: return "coils";
    case Op::heartbeat: return "heartbeat";
    case Op::axis_settings: return "axis_settings";
    case Op::command: return "command";
  }
  return "?";
}

// How evenly the clients were served: requests per client. A server that
// lets some clients go round again while others wait shows a wide spread.
std::vector<double> requests_per_client(const std::vector<ClientResult>& results) {
  std::vector<double> counts;
  for (const auto& r : results) counts.push_back(static_cast<double>(r.latency_us.size()));
  std::sort(counts.begin(), counts.end());
  return counts;
}

// The 10th percentile of requests per client over the 90th: 1 when every
// client was served alike.
double client_spread(const std::vector<ClientResult>& results) {
  const auto counts = requests_per_client(results);
  if (counts.size() < 2 || counts[counts.size() * 9 / 10] <= 0) return 1.0;
  return counts[counts.size() / 10] / counts[counts.size() * 9 / 10];
}

void print_spread(const std::vector<ClientResult>& results) {
  if (results.size() < 2) return;
  const auto counts = requests_per_client(results);
  std::printf("PER_CLIENT requests min %.0f p10 %.0f p50 %.0f p90 %.0f max %.0f\n", counts.front(),
              counts[counts.size() / 10], counts[counts.size() / 2], counts[counts.size() * 9 / 10], counts.back());
}

// One line per request kind of the mix, so a tail can be traced to the
// requests that make it.
void print_by_request(const Config& c, const std::vector<ClientResult>& results) {
  std::vector<Op> kinds = c.ops;
  std::sort(kinds.begin(), kinds.end());
  kinds.erase(std::unique(kinds.begin(), kinds.end()), kinds.end());
  if (kinds.size() < 2) return;
  std::printf("BY_REQUEST");
  for (const Op k : kinds) {
    std::vector<double> mine;
    for (const auto& r : results)
      for (std::size_t i = 0; i < r.latency_us.size(); ++i)
        if (r.latency_op[i] == k) mine.push_back(r.latency_us[i]);
    std::printf(" %s=%zu/p50:%.0f/p99:%.0f", op_name(k), mine.size(), bench::percentile(mine, 0.50),
                bench::percentile(mine, 0.99));
  }
  std::printf("\n");
}

struct HomeResult {
  std::uint64_t commands = 0;
  long cycles_before = -1, cycles_after = -1;
};

long read_u32(modbus_t* ctx, int addr) {
  std::uint16_t w[2];
  if (modbus_read_input_registers(ctx, addr, 2, w) != 2) return -1;
  return (long{w[0]} << 16) | w[1];
}

void run_home(const Config& c, HomeResult& h, const std::atomic<bool>& go, const std::atomic<std::int64_t>& deadline_ns) {
  Config side = c;
  side.rtu.clear();
  modbus_t* ctx = mb_connect(side);
  if (!ctx) return;
  h.cycles_before = read_u32(ctx, 3);  // status.homing_cycles
  while (!go) std::this_thread::yield();
  while (bench::now_ns() < deadline_ns) {
    std::uint16_t state = 0;
    if (modbus_read_input_registers(ctx, 1, 1, &state) == 1 && state != 1) {  // status.state 1 = homing
      if (modbus_write_bit(ctx, 0, 1) == 1) ++h.commands;                     // cmd.home_all
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  h.cycles_after = read_u32(ctx, 3);
  modbus_close(ctx);
  modbus_free(ctx);
}

}  // namespace

int main(int argc, char** argv) {
  bench::Args a(argc, argv,
                {{"host", "127.0.0.1"}, {"port", "1502"}, {"clients", "1"}, {"duration", "3"}, {"mix", "mixed"},
                 {"unit", "1"}, {"write-unit", "247"}, {"read-addr", "100"}, {"write-addr", "102"},
                 {"durable-addr", "120"}, {"requests", "0"}, {"raw", "false"}, {"home", "false"}, {"rtu", ""},
                 {"baud", "19200"}, {"parity", "E"}, {"pause-ms", "0"}, {"sync", "false"}});
  Config c;
  c.host = a.str("host");
  c.port = static_cast<int>(a.num("port"));
  c.clients = static_cast<int>(a.num("clients"));
  c.duration_s = a.real("duration");
  c.mix = a.str("mix");
  c.unit = static_cast<int>(a.num("unit"));
  c.write_unit = static_cast<int>(a.num("write-unit"));
  c.read_addr = static_cast<int>(a.num("read-addr"));
  c.write_addr = static_cast<int>(a.num("write-addr"));
  c.durable_addr = static_cast<int>(a.num("durable-addr"));
  c.max_requests = a.num("requests");
  c.pause_ms = static_cast<int>(a.num("pause-ms"));
  c.raw = a.flag("raw");
  c.home = a.flag("home");
  c.rtu = a.str("rtu");
  c.baud = static_cast<int>(a.num("baud"));
  c.parity = a.str("parity").empty() ? 'E' : a.str("parity")[0];
  if (c.mix == "read10") c.ops = {Op::read10};
  else if (c.mix == "read125") c.ops = {Op::read125};
  else if (c.mix == "write10") c.ops = {Op::write10};
  else if (c.mix == "mixed") c.ops = {Op::read10, Op::read125, Op::read10, Op::write10};
  else if (c.mix == "durable") c.ops = {Op::durable};
  else if (c.mix == "production")
    c.ops = {Op::status, Op::axis_inputs, Op::discretes, Op::coils, Op::heartbeat, Op::status, Op::axis_settings, Op::command};
  else {
    std::fprintf(stderr, "modbus_load: --mix read10|read125|write10|mixed|durable\n");
    return 2;
  }
  if (c.clients < 1 || c.duration_s <= 0 || (!c.rtu.empty() && (c.clients != 1 || c.raw))) {
    std::fprintf(stderr, "modbus_load: --clients >= 1 (1 with --rtu, no --raw), --duration > 0\n");
    return 2;
  }

  std::vector<ClientResult> results(static_cast<std::size_t>(c.clients));
  std::vector<std::thread> threads;
  std::atomic<bool> go{false};
  std::atomic<std::int64_t> deadline{INT64_MAX};
  Hold hold;
  Hold* const held = a.flag("sync") ? &hold : nullptr;
  for (std::size_t i = 0; i < results.size(); ++i)
    threads.emplace_back([&, i] { run_client(c, static_cast<int>(i), results[i], go, deadline, held); });
  HomeResult home;
  std::thread home_thread;
  if (c.home) home_thread = std::thread([&] { run_home(c, home, go, deadline); });
  std::this_thread::sleep_for(std::chrono::milliseconds(100 + 5 * c.clients));  // connections settle
  char line[16];
  if (held) {
    std::printf("WINDOW ready\n");
    std::fflush(stdout);
    [[maybe_unused]] const char* got = std::fgets(line, sizeof line, stdin);  // EOF starts too
  }
  const std::int64_t start = bench::now_ns();
  deadline = start + static_cast<std::int64_t>(c.duration_s * 1e9);
  const bench::SelfCounters before = bench::SelfCounters::now();
  go = true;
  double elapsed_s = 0;
  std::string counters;
  if (held) {
    hold.wait_for(c.clients);
    elapsed_s = (bench::now_ns() - start) / 1e9;
    counters = bench::SelfCounters::now().since(before);
    std::printf("WINDOW end\n");
    std::fflush(stdout);
    [[maybe_unused]] const char* got = std::fgets(line, sizeof line, stdin);  // EOF releases too
    hold.release();
    for (auto& t : threads) t.join();
  } else {
    for (auto& t : threads) t.join();
    elapsed_s = (bench::now_ns() - start) / 1e9;
    counters = bench::SelfCounters::now().since(before);
  }
  if (home_thread.joinable()) home_thread.join();

  std::vector<double> all;
  std::uint64_t ok = 0, exc = 0, exc06 = 0, terr = 0, reconnects = 0, never = 0;
  for (auto& r : results) {
    all.insert(all.end(), r.latency_us.begin(), r.latency_us.end());
    ok += r.ok;
    exc += r.exceptions;
    exc06 += r.exc06;
    terr += r.transport_errors;
    reconnects += r.reconnects;
    never += r.ok + r.exceptions == 0;
  }
  const double rps = static_cast<double>(ok + exc) / elapsed_s;
  const double p50 = bench::percentile(all, 0.50), p99 = bench::percentile(all, 0.99),
               p999 = bench::percentile(all, 0.999);
  const double mx = all.empty() ? 0 : *std::max_element(all.begin(), all.end());
  const std::uint64_t errors = exc - exc06 + terr;
  std::printf("%s %s clients=%d %.2fs: %.0f req/s, latency p50 %.1f us p99 %.1f us p99.9 %.1f us max %.1f us, "
              "errors %llu (exceptions %llu of which 06: %llu, transport %llu)\n",
              c.rtu.empty() ? (c.raw ? "raw-tcp" : "tcp") : "rtu", c.mix.c_str(), c.clients, elapsed_s, rps, p50, p99,
              p999, mx, (unsigned long long)errors, (unsigned long long)exc, (unsigned long long)exc06,
              (unsigned long long)terr);
  std::printf("RESULT mix=%s clients=%d seconds=%.3f requests=%llu rps=%.1f p50_us=%.1f p99_us=%.1f p999_us=%.1f "
              "max_us=%.1f errors=%llu exceptions=%llu exc06=%llu transport_errors=%llu reconnects=%llu "
              "idle_clients=%llu home_commands=%llu homing_cycles=%ld client_spread=%.3f%s\n",
              c.mix.c_str(), c.clients, elapsed_s, (unsigned long long)(ok + exc), rps, p50, p99, p999, mx,
              (unsigned long long)errors, (unsigned long long)exc, (unsigned long long)exc06,
              (unsigned long long)terr, (unsigned long long)reconnects, (unsigned long long)never,
              (unsigned long long)home.commands,
              home.cycles_after >= 0 && home.cycles_before >= 0 ? home.cycles_after - home.cycles_before : -1L,
              client_spread(results), counters.c_str());
  print_spread(results);
  print_by_request(c, results);
  return 0;
}
