// Warnings about the server's TLS files that do not stop it from starting.
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <sys/stat.h>

#include <cstdio>

#include "tls/certificate.hpp"
#include "tls/context.hpp"

namespace tls {
namespace {

void key_mode(const std::string& key, std::vector<std::string>& out) {
  struct stat st {};
  if (key.empty() || ::stat(key.c_str(), &st) != 0) return;
  if ((st.st_mode & S_IRWXO) == 0) return;
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
  out.push_back("private key " + key + " may be read by every user of this machine (mode " + mode +
                "): make it readable by its owner and the group homingd runs in only (chmod 640, or 600)");
}

void crl_dates(const std::string& path, std::vector<std::string>& out) {
  if (path.empty()) return;
  Bio in(BIO_new_file(path.c_str(), "r"));
  if (!in) return;
  while (Crl crl{PEM_read_bio_X509_CRL(in.get(), nullptr, nullptr, nullptr)}) {
    const ASN1_TIME* next = X509_CRL_get0_nextUpdate(crl.get());
    const ASN1_TIME* last = X509_CRL_get0_lastUpdate(crl.get());
    if (next && X509_cmp_current_time(next) < 0)
      out.push_back("CRL " + path + " expired at " + time_text(next) +
                    " (its next update): every client certificate is refused with \"CRL has expired\" until a "
                    "current CRL from the CA is installed there (then SIGHUP or restart)");
    else if (last && X509_cmp_current_time(last) > 0)
      out.push_back("CRL " + path + " is not valid before " + time_text(last) +
                    ": every client certificate is refused until then; check this machine's clock");
  }
  ERR_clear_error();  // the end of the file reads as "no start line"
}

}  // namespace

std::vector<std::string> server_file_warnings(const ServerFiles& files) {
  std::vector<std::string> out;
  key_mode(files.key, out);
  crl_dates(files.crl, out);
  return out;
}

}  // namespace tls
