#pragma once
// Modbus RTU on a serial line with libmodbus (framing by function code, CRC
// check). libmodbus drops frames for other unit ids before their CRC is
// checked, so RTU serves the module's unit id (and broadcast 0) only; the
// simulator unit is reached over TCP.
#include <atomic>
#include <cstdint>
#include <expected>
#include <string>

#include "request_handler.hpp"

typedef struct _modbus modbus_t;

namespace server {

struct RtuConfig {
  std::string device;
  int baud = 19200;
  char parity = 'E';
  int stop_bits = 1;
  int unit_id = 1;
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
  RtuConfig config_;
  RequestHandler& handler_;
  modbus_t* ctx_ = nullptr;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> bad_frames_{0};
};

}  // namespace server
