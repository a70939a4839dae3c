#pragma once
// A command coil written as an operator does: wait until the module judged
// it and until whatever it started has come to rest (X, Y and Z).
#include <chrono>
#include <cstdint>
#include <string>

#include "daemon.hpp"

namespace e2e {

inline bool at_rest(Client& c) {
  if (c.read("status.homing") != 0) return false;
  for (const char* a : {"x", "y", "z"})
    if (c.read(std::string("axis.") + a + ".busy") != 0) return false;
  return true;
}

// The command's result (status.last_command_result).
inline std::int64_t command(Client& c, const std::string& coil) {
  using namespace std::chrono_literals;
  const std::int64_t count = c.read("status.command_count");
  REQUIRE(c.write(coil, 1) == 0);
  REQUIRE(wait_until([&] { return c.read("status.command_count") != count; }, 5s));
  const std::int64_t result = c.read("status.last_command_result");
  REQUIRE(wait_until([&] { return at_rest(c); }, 60s));
  return result;
}

}  // namespace e2e
