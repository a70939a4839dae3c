#pragma once
// HOST or HOST:PORT as --tcp and --tls take it; a port outside 1..65535 or not
// a number is the user's mistake, named with the option.
#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace homingctl {

inline std::pair<std::string, int> host_and_port(const std::string& address, int default_port,
                                                 std::string_view option) {
  const auto colon = address.rfind(':');
  if (colon == std::string::npos) return {address, default_port};
  const std::string port_text = address.substr(colon + 1);
  std::size_t used = 0;
  int port = 0;
  try {
    port = std::stoi(port_text, &used);
  } catch (...) {
    used = 0;
  }
  if (used == 0 || used != port_text.size() || port < 1 || port > 65535)
    throw std::invalid_argument(
        fmt::format("{} {}: expected HOST or HOST:PORT, PORT from 1 to 65535", option, address));
  return {address.substr(0, colon), port};
}

}  // namespace homingctl
