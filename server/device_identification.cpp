#include "device_identification.hpp"

#include <array>
#include <string_view>

#include "registers/errors.hpp"

namespace server {

Reply device_identification(const DeviceIdRequest& request) {
  constexpr auto fc = static_cast<std::uint8_t>(FunctionCode::encapsulated_interface);
  static constexpr std::array<std::string_view, 7> kObjects{
      "Homing Module Works", "HM-6", "0.1.0", "https://example.invalid/homing-module", "Homing module",
      "HM-6 Modbus homing controller", "homingd"};
  const std::uint8_t code = request.read_code;
  std::uint8_t object = request.object_id;
  const std::uint8_t last = code == 1 ? 2 : 6;  // basic: 0..2; regular: 0..6 (no extended objects)
  if (code == 4) {
    if (object > 6) return exception_reply(fc, static_cast<std::uint8_t>(registers::ExceptionCode::illegal_data_address));
  } else if (object > last) {
    object = 0;  // stream access from an unknown object restarts at 0
  }
  Reply reply{true, {fc, 0x0E, code, 0x82 /* regular, stream and individual */, 0x00, 0x00, 0x00}};
  std::uint8_t count = 0;
  const std::uint8_t first = object, stop = code == 4 ? object : last;
  for (std::uint8_t id = first; id <= stop; ++id) {
    const auto text = kObjects[id];
    reply.pdu.push_back(id);
    reply.pdu.push_back(static_cast<std::uint8_t>(text.size()));
    reply.pdu.insert(reply.pdu.end(), text.begin(), text.end());
    ++count;
  }
  reply.pdu[6] = count;
  return reply;
}

}  // namespace server
