#include "rtu_server.hpp"

#include <modbus/modbus.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <poll.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

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
  return {};
}

void RtuServer::run() {
  ClientInfo broadcast_info{0, Transport::rtu, "broadcast"};
  broadcast_info.broadcast = true;
  const ClientInfo unit_info{0, Transport::rtu, "unit " + std::to_string(config_.unit_id)};
  const int fd = modbus_get_socket(ctx_);
  RtuFramer framer(static_cast<std::uint8_t>(config_.unit_id));
  std::array<std::uint8_t, MODBUS_RTU_MAX_ADU_LENGTH> chunk{};
  while (!stop_) {
    // Idle: wake up regularly to notice stop(). Inside a frame: its bytes must
    // follow within the byte timeout, else the frame ends there.
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, wait_ms(framer.pending()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) {
      if (auto r = framer.silence()) take(*r, broadcast_info, unit_info);
      release_if_silent(unit_info);
      continue;
    }
    const ssize_t n = ::read(fd, chunk.data(), chunk.size());
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) {
      spdlog::error("rtu: reading {} failed ({}); the serial line is no longer served", config_.device,
                    n == 0 ? "end of file" : std::strerror(errno));
      // An adapter unplugged or a cable fault: no master can release its jog any more.
      if (handler_.release_jogs(unit_info))
        spdlog::warn("rtu {}: the jog buttons the master held are released and the jog stopped", config_.device);
      return;
    }
    for (ssize_t i = 0; i < n; ++i)
      if (auto r = framer.push(chunk[static_cast<std::size_t>(i)])) take(*r, broadcast_info, unit_info);
    release_if_silent(unit_info);  // a bus busy with other units' frames: poll() never times out
  }
}

int RtuServer::wait_ms(bool pending) const {
  if (pending) return kByteTimeoutMs;
  if (config_.jog_release.count() <= 0 || silence_handled_) return kIdleWakeMs;
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(last_heard_ + config_.jog_release - Clock::now());
  return static_cast<int>(std::clamp<std::int64_t>(left.count(), 0, kIdleWakeMs));
}

void RtuServer::release_if_silent(const ClientInfo& master) {
  if (config_.jog_release.count() <= 0 || silence_handled_) return;
  const auto silent = Clock::now() - last_heard_;
  if (silent < config_.jog_release) return;
  silence_handled_ = true;
  // A panel holding a jog button keeps talking to the module; one that went
  // quiet (power, cable, crash) can no longer release it, and a serial line
  // has no disconnect to say so.
  if (handler_.release_jogs(master))
    spdlog::warn("rtu {}: no request from the master for {} ms (--rtu-jog-release-ms {}): the jog buttons it held "
                 "are released and the jog stopped; it starts again on the master's next press (a master that rewrites a "
                 "held coil every cycle presses it again with its first request)",
                 config_.device, std::chrono::duration_cast<std::chrono::milliseconds>(silent).count(),
                 config_.jog_release.count());
}

void RtuServer::take(const RtuFramer::Result& r, const ClientInfo& broadcast_info, const ClientInfo& unit_info) {
  if (r.event != RtuFramer::Event::frame) {
    handler_.bus_event(Transport::rtu, r.event == RtuFramer::Event::overrun ? BusEvent::overrun : BusEvent::comm_error);
    ++bad_frames_;
    spdlog::debug("rtu: bad frame ({}), {} so far; carrying on",
                  r.event == RtuFramer::Event::overrun ? "overrun" : "CRC", bad_frames_.load());
    return;
  }
  handler_.bus_event(Transport::rtu, BusEvent::message);
  const std::uint8_t unit = r.frame[0];
  if (unit != config_.unit_id && unit != 0) return;  // another device on the bus
  last_heard_ = Clock::now();
  silence_handled_ = false;
  const auto pdu = std::span<const std::uint8_t>(r.frame.data() + 1, r.frame.size() - 3);
  const Reply reply = handler_.handle(unit, pdu, unit == 0 ? broadcast_info : unit_info);
  last_heard_ = Clock::now();  // the time spent answering is no silence of the master
  if (!reply.send || unit == 0) return;  // broadcasts are never answered
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

}  // namespace server
