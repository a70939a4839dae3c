#pragma once
// Modbus RTU on a serial line: libmodbus opens and configures the port, the
// frames are cut by server/rtu_framer.hpp (libmodbus cannot frame functions
// 08, 20 and 43). RTU serves the module's unit id (and broadcast 0) only; the
// simulator unit is reached over TCP. Every frame on the line, for any unit,
// is counted for function 08.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <expected>
#include <string>

#include "request_handler.hpp"
#include "rtu_framer.hpp"

typedef struct _modbus modbus_t;

namespace server {

struct RtuConfig {
  std::string device;
  int baud = 19200;
  char parity = 'E';
  int stop_bits = 1;
  int unit_id = 1;
  // No request for the module (its unit or a broadcast) for this long
  // releases the jog buttons the master holds; zero: never.
  std::chrono::milliseconds jog_release{1000};
};

class RtuServer {
 public:
  RtuServer(RtuConfig config, RequestHandler& handler);
  ~RtuServer();
  RtuServer(const RtuServer&) = delete;
  RtuServer& operator=(const RtuServer&) = delete;

  std::expected<void, std::string> open();
  void run();  // until stop(); never exits on a bad frame
  void stop() { stop_ = true; }
  std::uint64_t bad_frames() const { return bad_frames_.load(); }

 private:
  // A frame's bytes follow each other within this; 200 ms idle wake-ups to notice stop().
  static constexpr int kByteTimeoutMs = 100;
  static constexpr int kIdleWakeMs = 200;
  void take(const RtuFramer::Result& result, const ClientInfo& broadcast_info, const ClientInfo& unit_info);
  // How long poll() may sleep before the master's silence must be looked at.
  int wait_ms(bool pending) const;
  void release_if_silent(const ClientInfo& master);

  using Clock = std::chrono::steady_clock;
  Clock::time_point last_heard_ = Clock::now();
  bool silence_handled_ = false;  // the jogs were released (or none held) since the master was last heard

  RtuConfig config_;
  RequestHandler& handler_;
  modbus_t* ctx_ = nullptr;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> bad_frames_{0};
};

}  // namespace server
