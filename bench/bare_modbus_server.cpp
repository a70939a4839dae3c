// The protocol stack's own limit: a minimal libmodbus server that only
// answers from a mapping, in the shape of libmodbus's own examples
// (modbus_tcp_listen, one select() loop over every client, modbus_receive +
// modbus_reply). Single-threaded, as libmodbus servers are.
//
//   bare_modbus_server --port 1502            (TCP on 127.0.0.1)
//   bare_modbus_server --rtu /dev/pts/N       (RTU, 19200 8E1 unless told)
//
// Prints "listening" once ready; SIGTERM/SIGINT end it.
#include <errno.h>
#include <modbus/modbus.h>
#include <signal.h>
#include <sys/select.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "bench_util.hpp"

namespace {
volatile sig_atomic_t stop = 0;
void on_signal(int) { stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  bench::Args a(argc, argv,
                {{"host", "127.0.0.1"}, {"port", "1502"}, {"rtu", ""}, {"baud", "19200"}, {"parity", "E"},
                 {"unit", "1"}});
  struct sigaction sa{};
  sa.sa_handler = on_signal;  // no SA_RESTART: select() returns EINTR
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);

  // Every table 0..999, all zero: reads and writes anywhere in it succeed.
  modbus_mapping_t* map = modbus_mapping_new(1000, 1000, 1000, 1000);
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];

  if (!a.str("rtu").empty()) {
    modbus_t* ctx = modbus_new_rtu(a.str("rtu").c_str(), static_cast<int>(a.num("baud")), a.str("parity")[0], 8, 1);
    modbus_set_slave(ctx, static_cast<int>(a.num("unit")));
    if (!ctx || modbus_connect(ctx) < 0) {
      std::fprintf(stderr, "bare_modbus_server: %s: %s\n", a.str("rtu").c_str(), modbus_strerror(errno));
      return 1;
    }
    std::printf("bare_modbus_server: listening on rtu %s\n", a.str("rtu").c_str());
    std::fflush(stdout);
    while (!stop) {
      const int rc = modbus_receive(ctx, query);
      if (rc > 0) modbus_reply(ctx, query, rc, map);
      else if (rc < 0 && errno != EINTR) modbus_flush(ctx);
    }
    modbus_close(ctx);
    modbus_free(ctx);
    modbus_mapping_free(map);
    return 0;
  }

  modbus_t* ctx = modbus_new_tcp(a.str("host").c_str(), static_cast<int>(a.num("port")));
  int server = modbus_tcp_listen(ctx, 128);
  if (server < 0) {
    std::fprintf(stderr, "bare_modbus_server: port %s: %s\n", a.str("port").c_str(), modbus_strerror(errno));
    return 1;
  }
  std::printf("bare_modbus_server: listening on tcp %s:%s\n", a.str("host").c_str(), a.str("port").c_str());
  std::fflush(stdout);

  fd_set all;
  FD_ZERO(&all);
  FD_SET(server, &all);
  int fdmax = server;
  while (!stop) {
    fd_set ready = all;
    if (select(fdmax + 1, &ready, nullptr, nullptr, nullptr) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int fd = 0; fd <= fdmax; ++fd) {
      if (!FD_ISSET(fd, &ready)) continue;
      if (fd == server) {
        const int client = modbus_tcp_accept(ctx, &server);
        if (client >= 0 && client < FD_SETSIZE) {
          FD_SET(client, &all);
          if (client > fdmax) fdmax = client;
        } else if (client >= 0) {
          close(client);
        }
        continue;
      }
      modbus_set_socket(ctx, fd);
      const int rc = modbus_receive(ctx, query);
      if (rc > 0) {
        modbus_reply(ctx, query, rc, map);
      } else if (rc == -1) {
        close(fd);  // the client went away (or sent garbage)
        FD_CLR(fd, &all);
        if (fd == fdmax)
          while (fdmax > server && !FD_ISSET(fdmax, &all)) --fdmax;
      }
    }
  }
  close(server);
  modbus_free(ctx);
  modbus_mapping_free(map);
  return 0;
}
