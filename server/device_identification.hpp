#pragma once
// FC 43 / MEI 14 (read device identification): libmodbus 3.1.6 has none, so
// the module answers it itself, with its own identity (not the library's).
#include "pdu.hpp"
#include "request_decoder.hpp"

namespace server {

// Basic (objects 0..2) and regular (0..6) streams, or one object (code 4:
// 02 for an object the module does not have). No extended objects.
Reply device_identification(const DeviceIdRequest& request);

}  // namespace server
