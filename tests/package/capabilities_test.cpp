// homingd from the unpacked .deb run as systemd would run the unit: an
// unprivileged user holding exactly the unit's AmbientCapabilities (setpriv
// stands in for systemd), no new privileges. Needs root to hand out the
// capabilities, so tests/package/CMakeLists.txt registers it only when
// configured as root.
#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <regex>

#include "deb.hpp"

using namespace package_test;
using namespace std::chrono_literals;

namespace {

constexpr int kNobody = 65534;

// "CAP_NET_BIND_SERVICE CAP_SYS_NICE" -> "+net_bind_service,+sys_nice" (setpriv's spelling).
std::string setpriv_caps(const std::vector<std::string>& caps) {
  std::string out = "-all";
  for (auto c : caps) {
    c = c.substr(4);
    std::transform(c.begin(), c.end(), c.begin(), [](unsigned char ch) { return std::tolower(ch); });
    out += ",+" + c;
  }
  return out;
}

std::vector<std::string> unit_capabilities(const Unpacked& pkg) {
  const auto unit = parse_unit(e2e::read_file(pkg.in_root("/usr/lib/systemd/system/homingd.service")));
  std::vector<std::string> caps;
  for (const auto& v : unit.at("Service.AmbientCapabilities"))
    for (const auto& w : words(v)) caps.push_back(w);
  return caps;
}

std::vector<std::string> as_nobody_with(const std::vector<std::string>& caps) {
  const std::string set = setpriv_caps(caps);
  return {"/usr/bin/setpriv", "--reuid=" + std::to_string(kNobody), "--regid=" + std::to_string(kNobody),
          "--clear-groups", "--inh-caps=" + set, "--ambient-caps=" + set, "--bounding-set=" + set,
          "--no-new-privs"};
}

// A port below 1024 on loopback that is free now.
int free_privileged_port() {
  for (int port = 602; port < 1024; ++port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
    ::close(fd);
    if (ok) return port;
  }
  throw std::runtime_error("no free port below 1024 on 127.0.0.1");
}

// The unpacked package readable by the unprivileged user, and a directory it may write.
std::string prepare(const Unpacked& pkg) {
  ::chmod(pkg.dir().path().c_str(), 0755);
  const std::string state = pkg.dir().file("state");
  std::filesystem::create_directory(state);
  REQUIRE(::chown(state.c_str(), kNobody, kNobody) == 0);
  return state;
}

std::string proc_status_field(pid_t pid, const std::string& field) {
  std::istringstream in(e2e::read_file("/proc/" + std::to_string(pid) + "/status"));
  for (std::string line; std::getline(in, line);)
    if (line.starts_with(field + ":")) return line.substr(field.size() + 1);
  return {};
}

}  // namespace

TEST_CASE("with only the unit's capabilities, an unprivileged homingd listens below port 1024 and runs its loop on SCHED_FIFO") {
  REQUIRE(::geteuid() == 0);
  Unpacked pkg;
  const std::string state = prepare(pkg);
  const auto caps = unit_capabilities(pkg);
  REQUIRE(caps == std::vector<std::string>{"CAP_NET_BIND_SERVICE", "CAP_SYS_NICE"});

  e2e::DaemonOptions options;
  options.wrapper = as_nobody_with(caps);
  options.program = pkg.in_root("/usr/bin/homingd");
  options.port = free_privileged_port();
  options.db = state + "/homingd.db";
  options.time_scale = 1;
  options.extra = {"--config", pkg.in_root("/etc/homingd/homingd.toml")};
  e2e::Daemon d(options);

  auto client = e2e::Client::tcp(d.port());
  REQUIRE(modbus_connect(client.ctx()) == 0);
  CHECK(client.try_read("status.state"));
  CHECK_THAT(d.log(), Catch::Contains("control loop: SCHED_FIFO priority 20"));
  CHECK_THAT(proc_status_field(d.pid(), "Uid"), Catch::StartsWith("\t" + std::to_string(kNobody)));
  CHECK(proc_status_field(d.pid(), "NoNewPrivs") == "\t1");
  // Effective: CAP_NET_BIND_SERVICE (10) and CAP_SYS_NICE (23), nothing else.
  CHECK(proc_status_field(d.pid(), "CapEff") == "\t0000000000800400");
  CHECK(proc_status_field(d.pid(), "CapBnd") == "\t0000000000800400");
  CHECK(client.write("axis.x.seek_feedrate", *client.try_read("axis.x.seek_feedrate")) == 0);  // the db is writable
}

TEST_CASE("without CAP_SYS_NICE the unprivileged homingd runs its loop at normal priority and says how to grant it") {
  REQUIRE(::geteuid() == 0);
  Unpacked pkg;
  const std::string state = prepare(pkg);
  e2e::DaemonOptions options;
  options.wrapper = as_nobody_with({"CAP_NET_BIND_SERVICE"});
  options.program = pkg.in_root("/usr/bin/homingd");
  options.port = free_privileged_port();
  options.db = state + "/homingd.db";
  options.extra = {"--config", pkg.in_root("/etc/homingd/homingd.toml")};
  e2e::Daemon d(options);
  CHECK_THAT(d.log(), Catch::Contains("real-time scheduling refused") && Catch::Contains("CAP_SYS_NICE"));
}

TEST_CASE("without CAP_NET_BIND_SERVICE the unprivileged homingd cannot listen below port 1024 and says so") {
  REQUIRE(::geteuid() == 0);
  Unpacked pkg;
  const std::string state = prepare(pkg);
  const int port = free_privileged_port();
  auto argv = as_nobody_with({"CAP_SYS_NICE"});
  argv.insert(argv.end(), {pkg.in_root("/usr/bin/homingd"), "--config", pkg.in_root("/etc/homingd/homingd.toml"),
                           "--tcp", "127.0.0.1:" + std::to_string(port), "--db", state + "/homingd.db"});
  const auto r = e2e::run_program(argv, 30s);
  INFO(r.out << r.err);
  CHECK(r.code() == 1);
  CHECK_THAT(r.err, Catch::Contains(std::to_string(port)) && Catch::Contains("Permission denied"));
}
