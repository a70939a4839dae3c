#pragma once
// Modbus RTU framing of the bytes read from a serial line. libmodbus 3.1.6
// frames RTU requests by function code and knows nothing of function 08, 20
// or 43 (it takes their data bytes for the CRC), so the module frames them
// itself: a frame for this module with a known function code ends at that
// function's length (function 08 sub-function 00 may echo more words: the
// frame is extended word by word until its CRC matches); any other frame (for
// another unit on the bus, or a function the module does not know) ends where
// its CRC first matches. Silence on the line (the caller's byte timeout) ends
// a frame that never matched: a communication error.
//
// A bad frame does not leave the module deaf until the line falls silent (a
// master that retries at once, a busy multi-drop bus): after a frame for this
// module that fails its CRC, an overrun, or a noise byte no device has as its
// address (248-255, 0xFF: a line glitch), every byte ends a search for a
// request addressed to this unit that ends there (its unit id, its
// function's length, its CRC), so the next good request is answered as it
// completes. A search takes no broadcast, and ends at the first request
// found or at silence; outside one, another unit's frame is never searched
// (its data may hold any bytes). Pure: no I/O, no clock.
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace server {

class RtuFramer {
 public:
  enum class Event : std::uint8_t {
    frame,    // a whole frame whose CRC matches (unit id first, CRC last)
    bad_crc,  // a frame that failed its CRC (or was cut short)
    overrun,  // more bytes than the largest RTU ADU (256, or the byte count of a request for this module) without a frame
  };
  struct Result {
    Event event = Event::frame;
    std::vector<std::uint8_t> frame;  // Event::frame only
  };

  explicit RtuFramer(std::uint8_t own_unit) : own_unit_(own_unit) {}

  // One byte from the line; a result when it completes or breaks a frame.
  std::optional<Result> push(std::uint8_t byte);
  // The line stayed quiet for the byte timeout: a frame begun ends here.
  std::optional<Result> silence();
  // Bytes of a frame are waiting (the caller then polls with the byte timeout).
  bool pending() const { return !buf_.empty(); }

 private:
  std::optional<Result> check_own_frame(std::size_t length);
  // A request for this module that begins after the first byte and ends at
  // the last one: taken, with everything before it.
  std::optional<Result> own_frame_inside();
  std::size_t longest() const;  // bytes a frame may have so far before it is an overrun

  std::uint8_t own_unit_;
  std::vector<std::uint8_t> buf_;
  bool hunting_ = false;  // after a bad frame: the bytes kept are searched for a request, until silence
};

// The whole length (unit id to CRC) of a request for function `frame[1]`,
// once enough of the frame is there to know it: nullopt while more header
// bytes are needed, 0 for a function code the module does not know.
std::optional<std::size_t> rtu_request_length(std::span<const std::uint8_t> frame);

}  // namespace server
