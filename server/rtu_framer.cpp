#include "rtu_framer.hpp"

#include <modbus/modbus.h>

#include <span>

#include "pdu.hpp"

namespace server {
namespace {

bool crc_matches(std::span<const std::uint8_t> frame) {
  if (frame.size() < 4) return false;
  const std::size_t n = frame.size();
  const std::uint16_t crc = crc16(frame.first(n - 2));
  return frame[n - 2] == (crc & 0xFF) && frame[n - 1] == (crc >> 8);
}

constexpr std::uint8_t kDiagnostics = 0x08;
constexpr std::uint8_t kFirstReservedUnit = 248;

}  // namespace

std::optional<std::size_t> rtu_request_length(std::span<const std::uint8_t> f) {
  constexpr std::size_t kUnitFcCrc = 4;  // unit id, function code, CRC
  if (f.size() < 2) return std::nullopt;
  switch (f[1]) {
    case 1: case 2: case 3: case 4: case 5: case 6:
    case kDiagnostics:                                   // sub-function + one word (00 may have more)
      return kUnitFcCrc + 4;
    case 15: case 16:                                    // start, quantity, byte count, data
      if (f.size() < 7) return std::nullopt;
      return kUnitFcCrc + 5 + f[6];
    case 23:                                             // read start/quantity, write start/quantity, byte count
      if (f.size() < 11) return std::nullopt;
      return kUnitFcCrc + 9 + f[10];
    case 20:                                             // byte count, sub-requests
      if (f.size() < 3) return std::nullopt;
      return kUnitFcCrc + 1 + f[2];
    case 43:                                             // MEI type, read code, object id
      return kUnitFcCrc + 3;
    case 17:                                             // nothing after the function code
      return kUnitFcCrc;
    default:
      return 0;
  }
}

// The largest RTU ADU is 256 bytes. A request for this module whose byte
// count says more (a write of 124 registers or more) is read whole, so that
// it is answered with exception 03 (a bad quantity) rather than not at all.
std::size_t RtuFramer::longest() const {
  if (buf_.size() >= 2 && (buf_[0] == own_unit_ || buf_[0] == 0))
    if (const auto n = rtu_request_length(buf_); n && *n > MODBUS_RTU_MAX_ADU_LENGTH) return *n;
  return MODBUS_RTU_MAX_ADU_LENGTH;
}

std::optional<RtuFramer::Result> RtuFramer::check_own_frame(std::size_t length) {
  if (buf_.size() < length) return std::nullopt;
  if (crc_matches(buf_)) {
    Result r{Event::frame, std::move(buf_)};
    buf_.clear();
    return r;
  }
  // Function 08 sub-function 00 echoes any number of words: extend by words.
  if (buf_[1] == kDiagnostics && buf_[2] == 0 && buf_[3] == 0) return std::nullopt;
  hunting_ = true;  // its bytes are kept: a request may begin inside them
  return Result{Event::bad_crc, {}};
}

std::optional<RtuFramer::Result> RtuFramer::own_frame_inside() {
  const std::size_t n = buf_.size();
  for (std::size_t start = 1; start + 4 <= n; ++start) {
    // Addressed to this unit only: a broadcast is never answered, so one
    // missed after a line error costs nothing, while one read out of the bytes
    // that follow the error (another unit's frame may carry any data) would
    // be applied.
    if (buf_[start] != own_unit_) continue;
    const std::span<const std::uint8_t> candidate(buf_.data() + start, n - start);
    const auto length = rtu_request_length(candidate);
    if (!length || *length != candidate.size() || !crc_matches(candidate)) continue;
    Result r{Event::frame, {candidate.begin(), candidate.end()}};
    buf_.clear();
    hunting_ = false;
    return r;
  }
  return std::nullopt;
}

std::optional<RtuFramer::Result> RtuFramer::push(std::uint8_t byte) {
  buf_.push_back(byte);
  if (hunting_) {
    if (auto r = own_frame_inside()) return r;
    // The longest request for this module is searched for whole; older bytes go.
    constexpr std::size_t kKept = 2 * MODBUS_RTU_MAX_ADU_LENGTH;
    if (buf_.size() > kKept) buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(buf_.size() - kKept));
    return std::nullopt;
  }
  if (buf_.size() > longest()) {
    hunting_ = true;
    return Result{Event::overrun, {}};
  }
  // 248-255 are no device's address (reserved): a noise byte (a line glitch
  // reads as 0xFF), the error that starts a search.
  if (buf_.size() == 1 && buf_[0] >= kFirstReservedUnit) {
    hunting_ = true;
    return Result{Event::bad_crc, {}};
  }
  if (buf_.size() < 4) return std::nullopt;
  const bool ours = buf_[0] == own_unit_ || buf_[0] == 0;
  if (ours) {
    const auto length = rtu_request_length(buf_);
    if (!length) return std::nullopt;
    if (*length != 0) {
      // Past the function's length only function 08's echo may grow, by words.
      if (buf_.size() > *length && (buf_.size() - *length) % 2 != 0) return std::nullopt;
      return check_own_frame(buf_.size() < *length ? *length : buf_.size());
    }
  }
  // Another unit's frame (request or answer) or an unknown function: the
  // frame ends where its CRC first matches. Its data is not searched for a
  // request for this module: it may carry any bytes.
  if (!crc_matches(buf_)) return std::nullopt;
  Result r{Event::frame, std::move(buf_)};
  buf_.clear();
  return r;
}

std::optional<RtuFramer::Result> RtuFramer::silence() {
  const bool had = !buf_.empty() && !hunting_;  // a search follows an error already counted
  buf_.clear();
  hunting_ = false;
  if (had) return Result{Event::bad_crc, {}};
  return std::nullopt;
}

}  // namespace server
