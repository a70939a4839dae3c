// Warnings about the server's TLS files that let it start but will bite: a
// private key every user may read, a CRL past its next update.
#include <catch2/catch.hpp>

#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/temp_dir.hpp"
#include "tests/support/test_pki.hpp"
#include "tls/context.hpp"
#include "tls/handles.hpp"

namespace {

namespace fs = std::filesystem;

bool any_has(const std::vector<std::string>& lines, const std::string& a, const std::string& b) {
  for (const std::string& l : lines)
    if (l.find(a) != std::string::npos && l.find(b) != std::string::npos) return true;
  return false;
}

tls::ServerFiles files_with(const std::string& key, const std::string& crl) {
  const std::string dir = test_support::test_pki() + "/";
  return tls::ServerFiles{dir + "server.crt", key, dir + "ca.crt", crl};
}

// A CRL signed by the test CA whose validity lies days_from..days_to from now.
void write_crl(const std::string& path, long days_from, long days_to) {
  const std::string dir = test_support::test_pki() + "/";
  FILE* f = std::fopen((dir + "ca.crt").c_str(), "r");
  REQUIRE(f);
  X509* ca = PEM_read_X509(f, nullptr, nullptr, nullptr);
  std::fclose(f);
  f = std::fopen((dir + "ca.key").c_str(), "r");
  REQUIRE(f);
  EVP_PKEY* key = PEM_read_PrivateKey(f, nullptr, nullptr, nullptr);
  std::fclose(f);
  REQUIRE(ca);
  REQUIRE(key);
  tls::Crl crl(X509_CRL_new());
  X509_CRL_set_version(crl.get(), 1);
  X509_CRL_set_issuer_name(crl.get(), X509_get_subject_name(ca));
  ASN1_TIME* from = X509_time_adj_ex(nullptr, static_cast<int>(days_from), 0, nullptr);
  ASN1_TIME* to = X509_time_adj_ex(nullptr, static_cast<int>(days_to), 0, nullptr);
  X509_CRL_set1_lastUpdate(crl.get(), from);
  X509_CRL_set1_nextUpdate(crl.get(), to);
  REQUIRE(X509_CRL_sign(crl.get(), key, EVP_sha256()) > 0);
  f = std::fopen(path.c_str(), "w");
  REQUIRE(f);
  PEM_write_X509_CRL(f, crl.get());
  std::fclose(f);
  ASN1_TIME_free(from);
  ASN1_TIME_free(to);
  EVP_PKEY_free(key);
  X509_free(ca);
}

}  // namespace

TEST_CASE("a server key that every user may read is a start-up warning naming the file and the fix") {
  test_support::TempDir tmp("tls-warn");
  const std::string key = tmp.file("server.key");
  fs::copy_file(test_support::test_pki() + "/server.key", key);
  ::chmod(key.c_str(), 0644);
  const auto loose = tls::server_file_warnings(files_with(key, ""));
  CHECK(any_has(loose, key, "may be read by every user of this machine (mode 0644)"));
  CHECK(any_has(loose, key, "chmod 640"));
  ::chmod(key.c_str(), 0640);
  CHECK(tls::server_file_warnings(files_with(key, "")).empty());
  ::chmod(key.c_str(), 0601);  // others may write or run it, not read it: not this warning
  CHECK(tls::server_file_warnings(files_with(key, "")).empty());
  ::chmod(key.c_str(), 0600);
  // The server starts either way: a warning, not a refusal.
  CHECK(tls::server_context(files_with(key, "")));
}

TEST_CASE("a CRL past its next update is a warning that every client is refused until a current one is installed") {
  test_support::TempDir tmp("tls-warn");
  const std::string key = test_support::test_pki() + "/server.key";
  const std::string expired = tmp.file("expired-crl.pem");
  write_crl(expired, -30, -1);
  const auto w = tls::server_file_warnings(files_with(key, expired));
  CHECK(any_has(w, expired, "expired at"));
  CHECK(any_has(w, expired, "every client certificate that CA issued is refused"));
  CHECK(tls::server_context(files_with(key, expired)));  // loaded as before: the warning says what follows

  const std::string early = tmp.file("early-crl.pem");
  write_crl(early, 2, 30);
  CHECK(any_has(tls::server_file_warnings(files_with(key, early)), early, "check this machine's clock"));

  const std::string current = tmp.file("current-crl.pem");
  write_crl(current, -1, 30);
  CHECK(tls::server_file_warnings(files_with(key, current)).empty());
  // An old CRL beside a current one of the same CA: OpenSSL uses the current one.
  const std::string both = tmp.file("both-crl.pem");
  std::ofstream(both) << test_support::read_file(expired) << test_support::read_file(current);
  CHECK(tls::server_file_warnings(files_with(key, both)).empty());
  // The CRL the README's recipe makes is current.
  CHECK(tls::server_file_warnings(files_with(key, test_support::test_pki() + "/crl.pem")).empty());
}
