#pragma once
// Where a Modbus/TCP (Security) connection goes: HOST:PORT as homingd and
// homingctl take it on their command lines, and a host's IPv4 address.
#include <netinet/in.h>

#include <expected>
#include <optional>
#include <string>

namespace tls {

struct HostPort {
  std::string host;
  int port = 0;
};

// "HOST:PORT", or "HOST" alone when there is a default port. The error names
// the option and what is wrong: "--tcp: port 70000 is outside 1..65535".
std::expected<HostPort, std::string> split_host_port(const std::string& option, const std::string& text,
                                                     std::optional<int> default_port);

// host's IPv4 address: a dotted address as it is, a name looked up. The
// error reads "cannot resolve HOST: why". (libmodbus takes only dotted
// addresses, so homingctl resolves a name here first.)
std::expected<in_addr, std::string> resolve_ipv4(const std::string& host);

}  // namespace tls
