#include "write_log.hpp"

#include "registers/codec.hpp"

namespace server {

persistence::ChangeSource source_of(const ClientInfo& client) {
  return persistence::ChangeSource{std::string(transport_name(client.transport)),
                                   client.identity.empty() ? client.address : client.address + " " + client.identity};
}

std::string describe_changes(const std::vector<registers::Change>& changes, const registers::AxisKinds& kinds) {
  std::string out;
  for (const auto& c : changes) {
    if (!out.empty()) out += "; ";
    out += c.reg->name() + ": " + registers::format_value(*c.reg, c.old_raw, kinds) + " -> " +
           registers::format_value(*c.reg, c.new_raw, kinds);
  }
  return out;
}

}  // namespace server
