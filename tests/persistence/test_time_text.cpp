// The one time format of the history, the audit log and the settings file.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <ctime>
#include <optional>
#include <string>

#include "persistence/time_text.hpp"

using namespace persistence;

namespace {
// Sets TZ for one scope and puts the old value back.
class ZoneFor {
 public:
  explicit ZoneFor(const char* tz) {
    if (const char* old = std::getenv("TZ")) old_ = old;
    ::setenv("TZ", tz, 1);
    ::tzset();
  }
  ~ZoneFor() {
    if (old_) ::setenv("TZ", old_->c_str(), 1);
    else ::unsetenv("TZ");
    ::tzset();
  }

 private:
  std::optional<std::string> old_;
};
}  // namespace

TEST_CASE("the settings file's time is UTC in ISO 8601 whatever the local zone", "[persistence]") {
  ZoneFor zone("XXX-5");
  CHECK(time_text(0, TimeZone::utc) == "1970-01-01T00:00:00Z");
  CHECK(time_text(1714564987123, TimeZone::utc) == "2024-05-01T12:03:07Z");
}

TEST_CASE("history times are the local clock to the second", "[persistence]") {
  {
    ZoneFor zone("UTC0");
    CHECK(time_text(1714564987999, TimeZone::local) == "2024-05-01 12:03:07");
  }
  {
    ZoneFor zone("XXX-2");  // POSIX: two hours east of UTC
    CHECK(time_text(1714564987123, TimeZone::local) == "2024-05-01 14:03:07");
  }
}
