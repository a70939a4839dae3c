// The .deb's maintainer scripts, run from the unpacked package with every
// command that would change the system (adduser, install, systemctl,
// deb-systemd-helper...) replaced by a stub that logs its arguments: what
// dpkg -i, an upgrade, remove and purge would do, without doing it.
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <fstream>

#include "deb.hpp"
#include "notify_socket.hpp"

using namespace package_test;
using namespace std::chrono_literals;
using notify_test::ScopedEnv;

namespace {

// Every command the scripts may run to change the system, as a logging stub.
// getent answers from STUB_USERS / STUB_GROUPS; deb-systemd-helper
// was-enabled from STUB_WAS_ENABLED (0 = enabled).
constexpr const char* kStubbed[] = {"adduser", "addgroup", "useradd", "groupadd", "deluser", "delgroup",
                                    "userdel", "groupdel", "install", "mkdir", "chown", "chmod", "rm",
                                    "systemctl", "deb-systemd-helper", "deb-systemd-invoke"};

class Stubs {
 public:
  Stubs() {
    for (const char* name : kStubbed) {
      std::string body = "#!/bin/sh\necho \"" + std::string(name) + " $*\" >> \"$STUB_LOG\"\n";
      if (std::string(name) == "deb-systemd-helper")
        body += "for a in \"$@\"; do [ \"$a\" = was-enabled ] && exit \"${STUB_WAS_ENABLED:-0}\"; done\n";
      body += "exit 0\n";
      add(name, body);
    }
    add("getent",
        "#!/bin/sh\necho \"getent $*\" >> \"$STUB_LOG\"\n"
        "case \"$1\" in passwd) list=\"$STUB_USERS\";; group) list=\"$STUB_GROUPS\";; *) exit 2;; esac\n"
        "for n in $list; do [ \"$n\" = \"$2\" ] && { echo \"$2:x:999:999::/var/lib/homingd:/usr/sbin/nologin\"; exit 0; }; done\n"
        "exit 2\n");
  }
  std::string bin() const { return (dir_.path() / "bin").string(); }
  std::string log_path() const { return dir_.file("log"); }
  std::vector<std::string> log() const {
    std::vector<std::string> lines;
    std::istringstream in(e2e::read_file(log_path()));
    for (std::string l; std::getline(in, l);) lines.push_back(l);
    return lines;
  }

 private:
  void add(const std::string& name, const std::string& body) {
    std::filesystem::create_directories(bin());
    const std::string path = bin() + "/" + name;
    std::ofstream(path) << body;
    ::chmod(path.c_str(), 0755);
  }
  e2e::TempDir dir_;
};

struct Run {
  int code = -1;
  std::vector<std::string> log;
  std::string err;
};

Run run_script(const Unpacked& pkg, const std::string& script, const std::vector<std::string>& args,
               const std::string& users, const std::string& groups, bool was_enabled = true) {
  Stubs stubs;
  ScopedEnv path("PATH", stubs.bin() + ":/usr/bin:/bin:/usr/sbin:/sbin");
  ScopedEnv log("STUB_LOG", stubs.log_path());
  ScopedEnv u("STUB_USERS", users);
  ScopedEnv g("STUB_GROUPS", groups);
  ScopedEnv e("STUB_WAS_ENABLED", was_enabled ? "0" : "1");
  std::vector<std::string> argv{"/bin/sh", "-e", pkg.in_root("/DEBIAN/" + script)};
  argv.insert(argv.end(), args.begin(), args.end());
  const auto r = e2e::run_program(argv, 60s);
  return Run{r.code(), stubs.log(), r.err};
}

bool has(const std::vector<std::string>& log, const std::string& prefix) {
  return std::any_of(log.begin(), log.end(), [&](const std::string& l) { return l.starts_with(prefix); });
}

// Where the line starting with prefix is in the log (size() when absent).
std::size_t at(const std::vector<std::string>& log, const std::string& prefix) {
  return static_cast<std::size_t>(
      std::find_if(log.begin(), log.end(), [&](const std::string& l) { return l.starts_with(prefix); }) - log.begin());
}

std::string joined(const std::vector<std::string>& log) {
  std::string s;
  for (const auto& l : log) s += l + "\n";
  return s;
}

// With systemd running (/run/systemd/system), postinst also reloads and starts.
const bool kSystemdRuns = std::filesystem::is_directory("/run/systemd/system");

}  // namespace

TEST_CASE("postinst of a first install creates the homingd system user and /var/lib/homingd, and enables the unit") {
  Unpacked pkg;
  const auto r = run_script(pkg, "postinst", {"configure"}, "", "dialout");
  INFO(joined(r.log) << r.err);
  REQUIRE(r.code == 0);
  const auto& log = r.log;
  REQUIRE(has(log, "adduser --quiet --system --group --no-create-home --home /var/lib/homingd"));
  CHECK(log[at(log, "adduser --quiet --system")].ends_with(" homingd"));
  CHECK(has(log, "adduser --quiet homingd dialout"));  // serial lines for RTU
  CHECK_FALSE(has(log, "adduser --quiet homingd gpio"));  // no such group here
  CHECK(has(log, "install -d -o homingd -g homingd -m 0750 /var/lib/homingd"));
  CHECK(at(log, "adduser --quiet --system") < at(log, "install -d -o homingd"));
  CHECK(has(log, "deb-systemd-helper enable homingd.service"));
  CHECK(has(log, "systemctl --system daemon-reload") == kSystemdRuns);
  CHECK(has(log, "deb-systemd-invoke start homingd.service") == kSystemdRuns);
  CHECK_FALSE(has(log, "deb-systemd-invoke restart"));
}

TEST_CASE("postinst of an upgrade keeps the existing user, an administrator's disabled unit, and restarts a running service") {
  Unpacked pkg;
  const auto r = run_script(pkg, "postinst", {"configure", "0.0.9"}, "homingd", "dialout gpio", false);
  INFO(joined(r.log) << r.err);
  REQUIRE(r.code == 0);
  const auto& log = r.log;
  CHECK_FALSE(has(log, "adduser --quiet --system"));
  CHECK(has(log, "adduser --quiet homingd dialout"));
  CHECK(has(log, "adduser --quiet homingd gpio"));
  CHECK(has(log, "install -d -o homingd -g homingd -m 0750 /var/lib/homingd"));
  CHECK_FALSE(has(log, "deb-systemd-helper enable"));
  CHECK(has(log, "deb-systemd-helper update-state homingd.service"));
  CHECK(has(log, "deb-systemd-invoke restart homingd.service") == kSystemdRuns);
  CHECK_FALSE(has(log, "deb-systemd-invoke start"));
}

TEST_CASE("prerm, postrm remove and postrm purge stop and forget the unit but keep the user and the settings database") {
  Unpacked pkg;
  const auto prerm = run_script(pkg, "prerm", {"remove"}, "homingd", "dialout");
  INFO(joined(prerm.log) << prerm.err);
  REQUIRE(prerm.code == 0);
  CHECK(has(prerm.log, "deb-systemd-invoke stop homingd.service") == kSystemdRuns);

  const auto upgrade = run_script(pkg, "prerm", {"upgrade", "0.1.1"}, "homingd", "dialout");
  REQUIRE(upgrade.code == 0);
  CHECK_FALSE(has(upgrade.log, "deb-systemd-invoke stop"));  // postinst of the new version restarts it

  const auto remove = run_script(pkg, "postrm", {"remove"}, "homingd", "dialout");
  INFO(joined(remove.log) << remove.err);
  REQUIRE(remove.code == 0);
  CHECK(has(remove.log, "deb-systemd-helper mask homingd.service"));

  const auto purge = run_script(pkg, "postrm", {"purge"}, "homingd", "dialout");
  INFO(joined(purge.log) << purge.err);
  REQUIRE(purge.code == 0);
  CHECK(has(purge.log, "deb-systemd-helper purge homingd.service"));
  CHECK(has(purge.log, "deb-systemd-helper unmask homingd.service"));
  for (const auto* log : {&prerm.log, &remove.log, &purge.log}) {
    CHECK_FALSE(has(*log, "rm "));
    CHECK_FALSE(has(*log, "deluser"));
    CHECK_FALSE(has(*log, "userdel"));
  }
}

TEST_CASE("the maintainer scripts are executable POSIX shell scripts that stop at the first failing command") {
  Unpacked pkg;
  for (const char* script : {"postinst", "prerm", "postrm"}) {
    INFO(script);
    const std::string path = pkg.in_root(std::string("/DEBIAN/") + script);
    struct stat st {};
    REQUIRE(::stat(path.c_str(), &st) == 0);
    CHECK((st.st_mode & 0777) == 0755);
    const std::string text = e2e::read_file(path);
    CHECK(text.starts_with("#!/bin/sh\n"));
    CHECK_THAT(text, Catch::Contains("\nset -e\n"));
    const auto syntax = e2e::run_program({"/bin/sh", "-n", path}, 20s);
    CHECK(syntax.code() == 0);
  }
}
