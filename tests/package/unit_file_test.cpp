// homingd.service as the .deb installs it: systemd's own checks
// (systemd-analyze verify, security) and what the unit promises.
#include <catch2/catch.hpp>

#include <fstream>
#include <regex>

#include "deb.hpp"

using namespace package_test;
using namespace std::chrono_literals;

namespace {

std::string unit_text(const Unpacked& pkg) {
  return e2e::read_file(pkg.in_root("/usr/lib/systemd/system/homingd.service"));
}

// The unit with ExecStart's program moved into the unpacked root, so that
// systemd-analyze finds the homingd it would start; saved as homingd.service.
std::string unit_for_analysis(const Unpacked& pkg) {
  const std::string text = std::regex_replace(unit_text(pkg), std::regex("\nExecStart=/"),
                                              "\nExecStart=" + pkg.root() + "/");
  const std::string path = pkg.dir().file("homingd.service");
  std::ofstream(path) << text;
  return path;
}

std::set<std::string> word_set(const std::vector<std::string>& values) {
  std::set<std::string> out;
  for (const auto& v : values)
    for (const auto& w : words(v)) out.insert(w);
  return out;
}

std::string one(const UnitKeys& unit, const std::string& key) {
  INFO(key);
  REQUIRE(unit.count(key) == 1);
  REQUIRE(unit.at(key).size() == 1);
  return unit.at(key).front();
}

}  // namespace

TEST_CASE("homingd.service passes systemd-analyze verify without a warning") {
  Unpacked pkg;
  const std::string unit = unit_for_analysis(pkg);
  const auto r = e2e::run_program({"systemd-analyze", "verify", unit}, 60s);
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  CHECK(r.code() == 0);
  CHECK(r.err.empty());

  // The check itself fails on a unit it should refuse.
  std::ofstream(unit, std::ios::app) << "\n[Service]\nNoSuchKey=1\n";
  const auto bad = e2e::run_program({"systemd-analyze", "verify", unit}, 60s);
  CHECK_THAT(bad.err, Catch::Contains("NoSuchKey"));
}

TEST_CASE("homingd.service rates OK or better in systemd-analyze security") {
  Unpacked pkg;
  const auto r = e2e::run_program({"systemd-analyze", "security", "--offline=yes", unit_for_analysis(pkg)}, 60s);
  INFO(r.out << r.err);
  std::smatch m;
  const std::string all = r.out + r.err;
  REQUIRE(std::regex_search(all, m, std::regex(R"(Overall exposure level for homingd\.service: ([0-9.]+))")));
  CHECK(std::stod(m[1]) <= 3.0);
}

TEST_CASE("homingd.service runs homingd as user homingd with only CAP_NET_BIND_SERVICE and CAP_SYS_NICE") {
  Unpacked pkg;
  const auto unit = parse_unit(unit_text(pkg));
  CHECK(one(unit, "Service.User") == "homingd");
  CHECK(one(unit, "Service.Group") == "homingd");
  const std::set<std::string> wanted{"CAP_NET_BIND_SERVICE", "CAP_SYS_NICE"};
  CHECK(word_set(unit.at("Service.AmbientCapabilities")) == wanted);
  CHECK(word_set(unit.at("Service.CapabilityBoundingSet")) == wanted);
  CHECK(one(unit, "Service.NoNewPrivileges") == "yes");
  CHECK(one(unit, "Service.ProtectSystem") == "strict");
  CHECK(one(unit, "Service.ProtectHome") == "yes");
  CHECK(one(unit, "Service.PrivateTmp") == "yes");
  // Its database: writable under StateDirectory=, the config's db.
  CHECK(one(unit, "Service.StateDirectory") == "homingd");
  CHECK_THAT(e2e::read_file(pkg.in_root("/etc/homingd/homingd.toml")),
             Catch::Contains("\ndb = \"/var/lib/homingd/homingd.db\""));
  // Not the settings that would close /dev to the serial line and the GPIO chip.
  CHECK(unit.count("Service.PrivateDevices") == 0);
  CHECK(unit.count("Service.ProtectClock") == 0);
  CHECK(unit.count("Service.DeviceAllow") == 0);
}

TEST_CASE("homingd.service is Type=notify with a watchdog, restarts on failure and starts homingd with the packaged config") {
  Unpacked pkg;
  const auto unit = parse_unit(unit_text(pkg));
  CHECK(one(unit, "Service.Type") == "notify");
  const std::string watchdog = one(unit, "Service.WatchdogSec");
  CHECK(std::regex_match(watchdog, std::regex("[1-9][0-9]*s")));
  CHECK(one(unit, "Service.Restart") == "on-failure");
  CHECK(one(unit, "Service.RestartPreventExitStatus") == "2");  // a config mistake is not restarted forever
  CHECK(words(one(unit, "Service.ExecStart")) ==
        std::vector<std::string>{"/usr/bin/homingd", "--config", "/etc/homingd/homingd.toml"});
  CHECK(one(unit, "Service.ExecReload") == "/bin/kill -HUP $MAINPID");  // reload: the TLS files again
  CHECK(one(unit, "Install.WantedBy") == "multi-user.target");
}
