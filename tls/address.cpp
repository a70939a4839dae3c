#include "tls/address.hpp"

#include <netdb.h>
#include <sys/socket.h>

#include <stdexcept>

namespace tls {

std::expected<HostPort, std::string> split_host_port(const std::string& option, const std::string& text,
                                                     std::optional<int> default_port) {
  const auto colon = text.rfind(':');
  if (default_port && colon == std::string::npos && !text.empty()) return HostPort{text, *default_port};
  const std::string usage = default_port ? "HOST or HOST:PORT (for example 0.0.0.0:802)"
                                         : "HOST:PORT (for example 127.0.0.1:1502)";
  if (colon == std::string::npos || colon == 0 || colon + 1 >= text.size())
    return std::unexpected(option + ": expected " + usage + ", got '" + text + "'");
  const std::string port = text.substr(colon + 1);
  int value = 0;
  try {
    std::size_t used = 0;
    value = std::stoi(port, &used);
    if (used != port.size()) throw std::invalid_argument(port);
  } catch (const std::exception&) {
    return std::unexpected(option + ": port '" + port + "' is not a number (1..65535)");
  }
  if (value < 1 || value > 65535)
    return std::unexpected(option + ": port " + port + " is outside 1..65535");
  return HostPort{text.substr(0, colon), value};
}

std::expected<in_addr, std::string> resolve_ipv4(const std::string& host) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &found); rc != 0)
    return std::unexpected("cannot resolve " + host + ": " + ::gai_strerror(rc));
  const in_addr address = reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr;
  ::freeaddrinfo(found);
  return address;
}

}  // namespace tls
