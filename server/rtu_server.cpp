#include "rtu_server.hpp"

#include <modbus/modbus.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <array>
#include <cerrno>

namespace server {

RtuServer::RtuServer(RtuConfig config, RequestHandler& handler) : config_(std::move(config)), handler_(handler) {}

RtuServer::~RtuServer() {
  if (ctx_) {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
}

std::expected<void, std::string> RtuServer::open() {
  ctx_ = modbus_new_rtu(config_.device.c_str(), config_.baud, config_.parity, 8, config_.stop_bits);
  if (!ctx_) return std::unexpected("--rtu " + config_.device + ": " + modbus_strerror(errno));
  modbus_set_slave(ctx_, config_.unit_id);
  if (modbus_connect(ctx_) < 0)
    return std::unexpected("--rtu " + config_.device + ": cannot open the serial device: " + modbus_strerror(errno));
  // Wake up regularly to notice stop(); a frame's bytes must follow closely.
  modbus_set_indication_timeout(ctx_, 0, 200000);
  modbus_set_byte_timeout(ctx_, 0, 100000);
  return {};
}

void RtuServer::run() {
  std::array<std::uint8_t, MODBUS_RTU_MAX_ADU_LENGTH> req{};
  const ClientInfo broadcast_info{0, Transport::rtu, "broadcast"};
  const ClientInfo unit_info{0, Transport::rtu, "unit " + std::to_string(config_.unit_id)};
  while (!stop_) {
    const int rc = modbus_receive(ctx_, req.data());
    if (rc == 0) continue;  // a frame for another unit on the bus
    if (rc < 0) {
      if (errno == ETIMEDOUT) continue;  // nothing came: just the stop check
      ++bad_frames_;
      spdlog::debug("rtu: bad frame ({}), {} so far; carrying on", modbus_strerror(errno), bad_frames_.load());
      modbus_flush(ctx_);
      continue;
    }
    if (rc < 4) continue;
    const std::uint8_t unit = req[0];
    const auto pdu = std::span<const std::uint8_t>(req.data() + 1, static_cast<std::size_t>(rc - 3));
    const Reply reply = handler_.handle(unit, pdu, unit == 0 ? broadcast_info : unit_info);
    if (!reply.send || unit == 0) continue;  // broadcasts are never answered
    const auto frame = rtu_frame(unit, reply.pdu);
    const int fd = modbus_get_socket(ctx_);
    std::size_t sent = 0;
    while (sent < frame.size()) {
      const ssize_t w = ::write(fd, frame.data() + sent, frame.size() - sent);
      if (w <= 0) {
        if (w < 0 && errno == EINTR) continue;
        break;
      }
      sent += static_cast<std::size_t>(w);
    }
  }
}

}  // namespace server
