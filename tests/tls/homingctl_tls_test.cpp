// homingctl --tls against the real homingd: the role in its certificate
// decides what it may do, and a refused link says why (exit code 3).
#include <catch2/catch.hpp>

#include "daemon.hpp"
#include "tests/support/test_pki.hpp"

#ifndef HOMINGCTL_PATH
#error "HOMINGCTL_PATH must be defined"
#endif

using namespace e2e;

namespace {

#define SHOW(r) INFO("exit " << (r).code() << "\nstdout:\n" << (r).out << "\nstderr:\n" << (r).err)

RunResult ctl_tls(const Daemon& d, std::string_view name, std::vector<std::string> args, std::string ca = "") {
  const TlsIdentity id = tls_identity(name);
  std::vector<std::string> argv{HOMINGCTL_PATH,         "--tls", "127.0.0.1:" + std::to_string(d.tls_port()),
                                "--cert",               id.cert, "--key",
                                id.key,                 "--ca",  ca.empty() ? id.ca : ca};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_program(argv, 60s);
}

DaemonOptions tls_daemon() {
  DaemonOptions o;
  o.tls = tls_server_options();
  return o;
}

}  // namespace

TEST_CASE("homingctl --tls with an engineer certificate shows the status, changes a setting, homes and reads a trace") {
  Daemon d(tls_daemon());
  auto r = ctl_tls(d, "engineer", {"status"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  CHECK(r.out.find("state: not_homed") != std::string::npos);
  r = ctl_tls(d, "engineer", {"set", "axis.x.seek_feedrate=1200"});
  SHOW(r);
  CHECK(r.code() == 0);
  r = ctl_tls(d, "engineer", {"get", "axis.x.seek_feedrate"});
  SHOW(r);
  CHECK(r.out.find("axis.x.seek_feedrate = 1200 mm/min") != std::string::npos);
  r = ctl_tls(d, "engineer", {"home", "x"});
  SHOW(r);
  REQUIRE(r.code() == 0);
  r = ctl_tls(d, "engineer", {"trace", "x"});  // FC 20, framed by homingctl itself, through the tunnel too
  SHOW(r);
  CHECK(r.code() == 0);
}

TEST_CASE("homingctl --tls with an operator certificate homes but cannot change a setting") {
  Daemon d(tls_daemon());
  auto r = ctl_tls(d, "operator", {"set", "axis.x.seek_feedrate=1200"});
  SHOW(r);
  CHECK(r.code() == 1);
  CHECK(r.err.find("exception 01") != std::string::npos);
  r = ctl_tls(d, "operator", {"home"});
  SHOW(r);
  CHECK(r.code() == 0);
  r = ctl_tls(d, "viewer", {"home", "--no-wait"});
  SHOW(r);
  CHECK(r.code() == 1);
}

TEST_CASE("homingctl --tls names the reason when the module refuses its certificate or it refuses the module's") {
  Daemon d(tls_daemon());
  auto r = ctl_tls(d, "revoked", {"status"});
  SHOW(r);
  CHECK(r.code() == 3);
  CHECK(r.err.find("certificate revoked") != std::string::npos);
  // Checked against a CA that did not sign the module's certificate.
  r = ctl_tls(d, "engineer", {"status"}, test_pki() + "/other-ca/ca.crt");
  SHOW(r);
  CHECK(r.code() == 3);
  CHECK(r.err.find("the server's certificate (CN=homingd,O=Homing module) was not accepted") != std::string::npos);
  r = run_program({HOMINGCTL_PATH, "--tls", "127.0.0.1:" + std::to_string(d.tls_port()), "status"}, 30s);
  SHOW(r);
  CHECK(r.code() == 2);
  CHECK(r.err.find("--tls needs --cert, --key and --ca") != std::string::npos);
}
