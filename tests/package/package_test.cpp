// The homingd .deb: its control file, where its files land, and the daemon
// and homingctl it installs, run from a throw-away root.
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <regex>

#include "deb.hpp"
#include "notify_socket.hpp"

using namespace package_test;
using namespace std::chrono_literals;

namespace {

std::string dpkg_architecture() {
  std::string arch = run_ok({"dpkg", "--print-architecture"});
  arch.erase(arch.find_last_not_of("\n ") + 1);
  return arch;
}

// The sonames a binary asks the dynamic loader for (DT_NEEDED).
std::vector<std::string> needed_libraries(const std::string& binary) {
  std::vector<std::string> out;
  const std::regex needed(R"(\(NEEDED\)\s+Shared library: \[([^\]]+)\])");
  const std::string dynamic = run_ok({"readelf", "-d", "-W", binary});
  for (std::sregex_iterator it(dynamic.begin(), dynamic.end(), needed), end; it != end; ++it)
    out.push_back((*it)[1]);
  return out;
}

// Where the dynamic loader finds each library of a binary (ldd: soname -> path).
std::map<std::string, std::string> loaded_paths(const std::string& binary) {
  std::map<std::string, std::string> out;
  const std::regex line(R"((\S+) => (/\S+) \(0x)");
  const std::string text = run_ok({"ldd", binary});
  for (std::sregex_iterator it(text.begin(), text.end(), line), end; it != end; ++it) out[(*it)[1]] = (*it)[2];
  return out;
}

// The Debian package that shipped the file the loader loads, with the names it
// Provides (dpkg-shlibdeps may name one of those: libspdlog1.10-fmt9).
std::set<std::string> names_of_owner(const std::string& soname, const std::string& loaded) {
  const auto canonical = std::filesystem::canonical(loaded);
  std::istringstream owners(run_ok({"dpkg", "-S", "*/" + soname}));  // every architecture's copy
  for (std::string line; std::getline(owners, line);) {
    const auto sep = line.find(": /");
    if (sep == std::string::npos) continue;
    std::error_code ec;
    if (std::filesystem::canonical(line.substr(sep + 2), ec) != canonical) continue;
    const std::string package = line.substr(0, line.find_first_of(":,"));
    std::set<std::string> names{package};
    for (const auto& p : depended_packages(run_ok({"dpkg-query", "-W", "-f=${Provides}", package}))) names.insert(p);
    return names;
  }
  throw std::runtime_error("no installed package ships " + loaded);
}

mode_t mode_of(const std::string& path) {
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  return st.st_mode & 07777;
}

// The unit's ExecStart with its paths moved into the unpacked root.
std::vector<std::string> exec_start_in_root(const Unpacked& pkg) {
  const auto unit = parse_unit(e2e::read_file(pkg.in_root("/usr/lib/systemd/system/homingd.service")));
  REQUIRE(unit.count("Service.ExecStart") == 1);
  auto argv = words(unit.at("Service.ExecStart").front());
  for (auto& a : argv)
    if (a.starts_with("/")) a = pkg.in_root(a);
  return argv;
}

}  // namespace

TEST_CASE("the .deb is package homingd at the project's version for this machine's architecture") {
  const auto fields = control_fields(run_ok({"dpkg-deb", "-f", deb_path()}));
  CHECK(fields.at("Package") == "homingd");
  CHECK(fields.at("Version") == HOMING_VERSION);
  CHECK(fields.at("Architecture") == dpkg_architecture());
  CHECK_FALSE(fields.at("Maintainer").empty());
  CHECK_THAT(fields.at("Description"), Catch::Contains("Modbus"));
}

TEST_CASE("the .deb depends on the Debian package of every shared library homingd and homingctl load, and on adduser") {
  Unpacked pkg;
  const auto fields = control_fields(pkg.control("control"));
  REQUIRE(fields.count("Depends") == 1);
  const auto depends = depended_packages(fields.at("Depends"));
  INFO("Depends: " << fields.at("Depends"));
  CHECK(depends.contains("adduser"));  // postinst creates the homingd user with it
  std::size_t libraries = 0;
  for (const char* binary : {"/usr/bin/homingd", "/usr/bin/homingctl"}) {
    const auto loaded = loaded_paths(pkg.in_root(binary));
    for (const auto& soname : needed_libraries(pkg.in_root(binary))) {
      INFO(binary << " needs " << soname);
      REQUIRE(loaded.contains(soname));
      const auto names = names_of_owner(soname, loaded.at(soname));
      INFO("shipped by " << *names.begin() << " (" << names.size() << " names with what it provides)");
      CHECK(std::any_of(names.begin(), names.end(), [&](const std::string& n) { return depends.contains(n); }));
      ++libraries;
    }
  }
  CHECK(libraries >= 8);  // libmodbus, libgpiod, libsqlite3, libsystemd, libfmt, libstdc++, libgcc, libc...
  for (const char* runtime : {"libmodbus5", "libgpiod2", "libsqlite3-0", "libsystemd0", "libc6"}) {
    INFO(runtime);
    CHECK(depends.contains(runtime));
  }
}

TEST_CASE("/etc/homingd/homingd.toml is the .deb's one conffile, so an upgrade keeps local changes") {
  Unpacked pkg;
  const auto conffiles = words(pkg.control("conffiles"));
  CHECK(conffiles == std::vector<std::string>{"/etc/homingd/homingd.toml"});
  CHECK(std::filesystem::is_regular_file(pkg.in_root("/etc/homingd/homingd.toml")));
  CHECK(mode_of(pkg.in_root("/etc/homingd/homingd.toml")) == 0644);
}

TEST_CASE("the .deb puts the programs, unit, config, maps and documents where a Debian system expects them, and nothing else") {
  Unpacked pkg;
  std::set<std::string> expected{
      "/usr/bin/homingd",
      "/usr/bin/homingctl",
      "/usr/lib/systemd/system/homingd.service",
      "/etc/homingd/homingd.toml",
      "/usr/share/doc/homingd/README.md",
      "/usr/share/doc/homingd/CHANGELOG.md",
      "/usr/share/doc/homingd/copyright",
  };
  const std::filesystem::path maps = std::filesystem::path(HOMING_SOURCE_DIR) / "hmi_maps";
  std::size_t map_files = 0;
  for (const auto& e : std::filesystem::directory_iterator(maps)) {
    const std::string installed = "/usr/share/homingd/hmi_maps/" + e.path().filename().string();
    expected.insert(installed);
    ++map_files;
    if (std::filesystem::exists(pkg.in_root(installed))) {
      INFO(installed);
      CHECK(e2e::read_file(pkg.in_root(installed)) == e2e::read_file(e.path().string()));
    }
  }
  CHECK(map_files >= 5);
  // The guides README.md links to (docs/, with what they link to in its folders), beside it.
  std::size_t doc_files = 0;
  const std::filesystem::path docs = std::filesystem::path(HOMING_SOURCE_DIR) / "docs";
  for (const auto& e : std::filesystem::recursive_directory_iterator(docs)) {
    if (!e.is_regular_file() || e.path().extension() != ".md") continue;
    const std::string installed = "/usr/share/doc/homingd/docs/" + e.path().lexically_relative(docs).string();
    expected.insert(installed);
    ++doc_files;
    if (std::filesystem::exists(pkg.in_root(installed))) {
      INFO(installed);
      CHECK(e2e::read_file(pkg.in_root(installed)) == e2e::read_file(e.path().string()));
    }
  }
  CHECK(doc_files >= 9);
  CHECK(pkg.files() == expected);
  CHECK(mode_of(pkg.in_root("/usr/bin/homingd")) == 0755);
  CHECK(mode_of(pkg.in_root("/usr/bin/homingctl")) == 0755);
  CHECK(e2e::read_file(pkg.in_root("/usr/share/doc/homingd/copyright")) ==
        e2e::read_file(std::string(HOMING_SOURCE_DIR) + "/LICENSE"));
  // Stripped: debugging symbols stay in the build.
  CHECK_THAT(run_ok({"file", "-L", pkg.in_root("/usr/bin/homingd")}), Catch::Contains("stripped") &&
                                                                        !Catch::Contains("not stripped"));
}

TEST_CASE("homingd from the unpacked .deb, started with the unit's command line and the packaged config, answers a Modbus read") {
  Unpacked pkg;
  const auto argv = exec_start_in_root(pkg);
  REQUIRE(argv.size() >= 3);
  CHECK(argv[0] == pkg.in_root("/usr/bin/homingd"));
  CHECK(std::find(argv.begin(), argv.end(), pkg.in_root("/etc/homingd/homingd.toml")) != argv.end());

  // The port and database the test picks; everything else from the package.
  e2e::DaemonOptions options;
  options.program = argv[0];
  options.extra.assign(argv.begin() + 1, argv.end());
  options.time_scale = 1;
  e2e::Daemon d(options);
  CHECK_THAT(d.listening_line(), Catch::Contains("backend sim") && Catch::Contains(d.db()));

  auto client = e2e::Client::tcp(d.port());
  REQUIRE(modbus_connect(client.ctx()) == 0);
  const auto state = client.try_read("status.state");
  CHECK(state);
  const auto seek = client.try_read("axis.x.seek_feedrate");
  CHECK(seek);
  CHECK(client.write("axis.x.seek_feedrate", *seek) == 0);  // a durable write into the test's database

  const auto status = d.stop(SIGTERM, 15s);
  REQUIRE(status);
  CHECK(WIFEXITED(*status));
  CHECK(WEXITSTATUS(*status) == 0);
}

TEST_CASE("homingctl from the unpacked .deb finds the daemon through the config file, a wildcard listen address on loopback") {
  Unpacked pkg;
  const auto argv = exec_start_in_root(pkg);
  e2e::DaemonOptions options;
  options.program = argv[0];
  options.extra.assign(argv.begin() + 1, argv.end());
  e2e::Daemon d(options);

  // The packaged config with the test's port and database, as an installer would edit it.
  std::string config = e2e::read_file(pkg.in_root("/etc/homingd/homingd.toml"));
  config = std::regex_replace(config, std::regex(R"(\ntcp = "[^"]*")"), "\ntcp = \"0.0.0.0:" + std::to_string(d.port()) + "\"");
  config = std::regex_replace(config, std::regex(R"(\ndb = "[^"]*")"), "\ndb = \"" + d.db() + "\"");
  REQUIRE_THAT(config, Catch::Contains("0.0.0.0:" + std::to_string(d.port())));
  const std::string edited = pkg.dir().file("homingd.toml");
  std::ofstream(edited) << config;

  notify_test::ScopedEnv env("HOMINGD_CONFIG", edited);
  const auto status = e2e::run_program({pkg.in_root("/usr/bin/homingctl"), "status"}, 30s);
  INFO(status.out << status.err);
  CHECK(status.code() == 0);
  const auto history = e2e::run_program({pkg.in_root("/usr/bin/homingctl"), "history"}, 30s);
  INFO(history.out << history.err);
  CHECK(history.code() == 0);
}
