#pragma once
// HOST or HOST:PORT as --tcp and --tls take it (tls::split_host_port, as
// homingd's options); a port outside 1..65535 or not a number is the user's
// mistake, named with the option.
#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include "tls/address.hpp"

namespace homingctl {

inline std::pair<std::string, int> host_and_port(const std::string& address, int default_port,
                                                 std::string_view option) {
  const auto split = tls::split_host_port(std::string(option), address, default_port);
  if (!split)
    throw std::invalid_argument(
        fmt::format("{} {}: expected HOST or HOST:PORT, PORT from 1 to 65535", option, address));
  return {split->host, split->port};
}

}  // namespace homingctl
