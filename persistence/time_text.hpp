#pragma once
// The one way the module writes a time for people: unix milliseconds as text,
// to the second. The history and the audit log show the technician's local
// clock; the settings file's header says UTC in ISO 8601, so a file read on
// another machine means the same moment.
#include <cstdint>
#include <string>

namespace persistence {

enum class TimeZone { local, utc };

// local: "2024-05-01 14:03:07"; utc: "2024-05-01T12:03:07Z".
std::string time_text(std::int64_t unix_ms, TimeZone zone);

}  // namespace persistence
