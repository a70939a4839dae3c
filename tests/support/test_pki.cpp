#include "tests/support/test_pki.hpp"

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <stdexcept>

#include "tests/support/process.hpp"
#include "tests/support/temp_dir.hpp"

#ifndef MAKE_CERTS_SCRIPT
#error "MAKE_CERTS_SCRIPT must name tools/tls/make-certs.sh"
#endif
#ifndef TEST_PKI_ROOT
#error "TEST_PKI_ROOT must name a directory of the build tree"
#endif

namespace test_support {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Made in a directory of its own, then renamed into place: a process sees
// all of it or none, and when two make it at once one rename wins.
std::string make_pki() {
  const std::string script = read_file(MAKE_CERTS_SCRIPT);
  if (script.empty()) throw std::runtime_error(std::string("cannot read ") + MAKE_CERTS_SCRIPT);
  const fs::path root(TEST_PKI_ROOT);
  const fs::path done = root / std::to_string(std::hash<std::string>{}(script));
  if (fs::exists(done / "crl.pem")) return done.string();
  fs::create_directories(root);
  const fs::path making = root / ("making-" + std::to_string(::getpid()));
  fs::remove_all(making);
  make_certs({"init", making.string(), "--test-set"});
  std::error_code ec;
  fs::rename(making, done, ec);
  if (ec) fs::remove_all(making);  // another process put its set there first
  if (!fs::exists(done / "crl.pem")) throw std::runtime_error("no test certificates in " + done.string());
  return done.string();
}

}  // namespace

void make_certs(std::vector<std::string> args) {
  const std::string what = "make-certs.sh " + (args.empty() ? std::string() : args.front());
  args.insert(args.begin(), {"bash", MAKE_CERTS_SCRIPT});
  const RunResult r = run_program(args, 120s);
  if (!r.exited() || r.code() != 0) throw std::runtime_error(what + " failed: " + r.out + r.err);
}

const std::string& test_pki() {
  static const std::string dir = make_pki();
  return dir;
}

TlsIdentity tls_identity(std::string_view name) {
  const std::string dir = test_pki() + "/";
  if (name.empty()) return {"", "", dir + "ca.crt"};
  return {dir + std::string(name) + ".crt", dir + std::string(name) + ".key", dir + "ca.crt"};
}

std::vector<std::string> tls_server_options(bool with_crl) {
  const std::string dir = test_pki() + "/";
  std::vector<std::string> o{"--tls-cert", dir + "server.crt", "--tls-key", dir + "server.key", "--tls-ca", dir + "ca.crt"};
  if (with_crl) o.insert(o.end(), {"--tls-crl", dir + "crl.pem"});
  return o;
}

}  // namespace test_support
