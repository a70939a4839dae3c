#include "local_daemon.hpp"

#include <toml++/toml.h>

#include <cstdlib>
#include <filesystem>
#include <limits>

namespace homingctl {
namespace {

// homingd's config keys are its long option names, with '-' or '_'.
const toml::node* key(const toml::table& t, std::string_view underscored) {
  if (const toml::node* n = t.get(underscored)) return n;
  std::string dashed(underscored);
  for (char& c : dashed)
    if (c == '_') c = '-';
  return t.get(dashed);
}

// CLI11 reads `unit = 3` and `unit = "3"` alike; so does this.
std::expected<std::optional<int>, std::string> int_key(const toml::table& t, std::string_view name,
                                                       const std::string& path) {
  const toml::node* n = key(t, name);
  if (!n) return std::optional<int>{};
  // An integer node only (toml++'s value<int64_t>() of a large float is undefined behaviour).
  if (const auto* v = n->as_integer()) {
    if (v->get() >= std::numeric_limits<int>::min() && v->get() <= std::numeric_limits<int>::max())
      return std::optional<int>{static_cast<int>(v->get())};
    return std::unexpected(path + ": " + std::string(name) + " is out of range");
  }
  if (auto s = n->value<std::string>()) {
    try {
      std::size_t used = 0;
      const int v = std::stoi(*s, &used);
      if (used == s->size()) return std::optional<int>{v};
    } catch (const std::exception&) {
    }
  }
  return std::unexpected(path + ": " + std::string(name) + " is not a whole number");
}

// The address to connect to for a listen address: a wildcard means this host.
std::expected<std::string, std::string> connect_address(const std::string& listen, const std::string& path) {
  const auto colon = listen.rfind(':');
  if (colon == std::string::npos || colon + 1 >= listen.size())
    return std::unexpected(path + ": tcp = \"" + listen + "\" is not HOST:PORT");
  std::string host = listen.substr(0, colon);
  if (host.empty() || host == "0.0.0.0" || host == "*" || host == "::" || host == "[::]") host = "127.0.0.1";
  return host + listen.substr(colon);
}

}  // namespace

DaemonConfigChoice choose_daemon_config(const std::string& explicit_path) {
  if (!explicit_path.empty()) return {explicit_path, true};
  if (const char* env = std::getenv("HOMINGD_CONFIG"); env && *env) return {env, true};
  return {kPackagedDaemonConfig, false};
}

std::expected<std::optional<LocalDaemon>, std::string> read_local_daemon(const DaemonConfigChoice& choice) {
  std::error_code ec;
  if (!choice.named && !std::filesystem::exists(choice.path, ec)) return std::optional<LocalDaemon>{};
  toml::table t;
  try {
    t = toml::parse_file(choice.path);
  } catch (const toml::parse_error& e) {
    return std::unexpected(choice.path + ": " + std::string(e.description()) + " (line " +
                           std::to_string(e.source().begin.line) + ")");
  }
  LocalDaemon d;
  d.path = choice.path;
  const toml::node* no_tcp = key(t, "no_tcp");
  const bool tcp_off = no_tcp && no_tcp->value_or(false);
  if (const toml::node* tcp = key(t, "tcp"); tcp && !tcp_off) {
    const auto listen = tcp->value<std::string>();
    if (!listen) return std::unexpected(choice.path + ": tcp is not a \"HOST:PORT\" string");
    auto address = connect_address(*listen, choice.path);
    if (!address) return std::unexpected(address.error());
    d.tcp = *address;
  } else if (!tcp_off) {
    d.tcp = "127.0.0.1:1502";  // homingd's own default
  }
  auto unit = int_key(t, "unit", choice.path);
  if (!unit) return std::unexpected(unit.error());
  d.unit = *unit;
  auto sim_unit = int_key(t, "sim_unit", choice.path);
  if (!sim_unit) return std::unexpected(sim_unit.error());
  d.sim_unit = *sim_unit;
  if (const toml::node* wo = key(t, "word_order")) {
    const std::string v = wo->value_or(std::string());
    if (v == "high-first") d.word_order = registers::WordOrder::high_first;
    else if (v == "low-first") d.word_order = registers::WordOrder::low_first;
    else return std::unexpected(choice.path + ": word_order is neither \"high-first\" nor \"low-first\"");
  }
  if (const toml::node* db = key(t, "db")) d.db = db->value<std::string>();
  return std::optional<LocalDaemon>{std::move(d)};
}

void apply_local_daemon(const LocalDaemon& local, const GivenOptions& given, ConnectionOptions& co, std::string& db) {
  if (!given.tcp && local.tcp) co.tcp = *local.tcp;
  if (!given.unit && local.unit) co.unit = *local.unit;
  if (!given.sim_unit && local.sim_unit) co.sim_unit = *local.sim_unit;
  if (!given.word_order && local.word_order) co.word_order = *local.word_order;
  if (!given.db && local.db) db = *local.db;
}

}  // namespace homingctl
