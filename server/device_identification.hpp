#pragma once
// Who the module says it is: FC 43 / MEI 14 (read device identification;
// libmodbus 3.1.6 has none, so the module answers it itself) and FC 17
// (report server id). The revision comes from the build, the rest from the
// configuration (a machine builder names the machine and may rebrand).
#include <cstdint>
#include <string>

#include "pdu.hpp"
#include "request_decoder.hpp"

#ifndef HOMING_VERSION
#error "HOMING_VERSION must be defined by the build (CMake's project version)"
#endif

namespace server {

struct DeviceIdentity {
  std::string vendor_name = "Homing Module Works";        // object 0
  std::string product_code = "HM-6";                       // object 1
  std::string revision = HOMING_VERSION;                   // object 2: the build's version
  std::string vendor_url;                                  // object 3: empty unless configured
  std::string product_name = "Homing module";              // object 4
  std::string model_name = "HM-6 Modbus homing controller";  // object 5
  std::string user_application_name = "homingd";           // object 6: the machine's name
};

// Longest configured text: every object of the regular stream fits one reply
// at this length only with "more follows", which device_identification() does.
inline constexpr std::size_t kMaxIdentityText = 100;

// Basic (objects 0..2) and regular (0..6) streams, or one object (code 4:
// 02 for an object the module does not have). No extended objects. Objects
// that do not fit one reply are continued with "more follows".
Reply device_identification(const DeviceIdRequest& request, const DeviceIdentity& identity);

// FC 17: server id (the unit id), run indicator ON, then
// "<product code> <revision> <user application name>".
Reply report_server_id(std::uint8_t unit, const DeviceIdentity& identity);

}  // namespace server
