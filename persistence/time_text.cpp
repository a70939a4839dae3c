#include "persistence/time_text.hpp"

#include <ctime>

namespace persistence {

std::string time_text(std::int64_t unix_ms, TimeZone zone) {
  const std::time_t t = static_cast<std::time_t>(unix_ms / 1000);
  std::tm tm{};
  if (zone == TimeZone::utc)
    gmtime_r(&t, &tm);
  else
    localtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, zone == TimeZone::utc ? "%Y-%m-%dT%H:%M:%SZ" : "%Y-%m-%d %H:%M:%S", &tm);
  return buf;
}

}  // namespace persistence
