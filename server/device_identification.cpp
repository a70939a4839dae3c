#include "device_identification.hpp"

#include <array>
#include <string_view>

#include "registers/errors.hpp"

namespace server {

Reply device_identification(const DeviceIdRequest& request, const DeviceIdentity& identity) {
  constexpr auto fc = static_cast<std::uint8_t>(FunctionCode::encapsulated_interface);
  const std::array<std::string_view, 7> objects{identity.vendor_name,  identity.product_code, identity.revision,
                                                identity.vendor_url,   identity.product_name, identity.model_name,
                                                identity.user_application_name};
  const std::uint8_t code = request.read_code;
  std::uint8_t object = request.object_id;
  const std::uint8_t last = code == 1 ? 2 : 6;  // basic: 0..2; regular: 0..6 (no extended objects)
  // The regular objects (3..6) are optional: one not configured (the vendor
  // URL without --vendor-url) is not there, rather than there and empty.
  const auto present = [&](std::uint8_t id) { return id < 3 || !objects[id].empty(); };
  if (code == 4) {
    if (object > 6 || !present(object))
      return exception_reply(fc, static_cast<std::uint8_t>(registers::ExceptionCode::illegal_data_address));
  } else if (object > last) {
    object = 0;  // stream access from an unknown object restarts at 0
  }
  constexpr std::size_t kMoreFollows = 4, kNextObject = 5, kCount = 6;
  Reply reply{true, {fc, 0x0E, code, 0x82 /* regular, stream and individual */, 0x00, 0x00, 0x00}};
  std::uint8_t count = 0;
  const std::uint8_t stop = code == 4 ? object : last;
  for (std::uint8_t id = object; id <= stop; ++id) {
    if (!present(id)) continue;
    const std::string_view text = objects[id].substr(0, 0xFF);
    if (count > 0 && reply.pdu.size() + 2 + text.size() > kMaxPdu) {
      reply.pdu[kMoreFollows] = 0xFF;  // the client asks again from this object
      reply.pdu[kNextObject] = id;
      break;
    }
    reply.pdu.push_back(id);
    reply.pdu.push_back(static_cast<std::uint8_t>(text.size()));
    reply.pdu.insert(reply.pdu.end(), text.begin(), text.end());
    ++count;
  }
  reply.pdu[kCount] = count;
  return reply;
}

Reply report_server_id(std::uint8_t unit, const DeviceIdentity& identity) {
  constexpr auto fc = static_cast<std::uint8_t>(FunctionCode::report_server_id);
  std::string text = identity.product_code + " " + identity.revision + " " + identity.user_application_name;
  constexpr std::size_t kRoom = kMaxPdu - 4;  // fc, byte count, server id, run indicator
  if (text.size() > kRoom) text.resize(kRoom);
  Reply reply{true, {fc, static_cast<std::uint8_t>(2 + text.size()), unit, 0xFF /* run indicator: ON */}};
  reply.pdu.insert(reply.pdu.end(), text.begin(), text.end());
  return reply;
}

}  // namespace server
