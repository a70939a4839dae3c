// Warnings about the server's TLS files that do not stop it from starting.
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include <sys/stat.h>

#include <cstdio>
#include <string>
#include <vector>

#include "tls/certificate.hpp"
#include "tls/context.hpp"

namespace tls {
namespace {

void key_mode(const std::string& key, std::vector<std::string>& out) {
  struct stat st {};
  if (key.empty() || ::stat(key.c_str(), &st) != 0) return;
  if ((st.st_mode & S_IROTH) == 0) return;
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
  out.push_back("private key " + key + " may be read by every user of this machine (mode " + mode +
                "): make it readable by its owner and the group homingd runs in only (chmod 640, or 600)");
}

std::string name_text(const X509_NAME* name) {
  Bio bio(BIO_new(BIO_s_mem()));
  if (!bio || !name || X509_NAME_print_ex(bio.get(), name, 0, XN_FLAG_RFC2253) < 0) return "?";
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio.get(), &data);
  return n > 0 && data ? std::string(data, static_cast<std::size_t>(n)) : std::string("?");
}

bool current(const X509_CRL* crl) {
  const ASN1_TIME* next = X509_CRL_get0_nextUpdate(crl);
  const ASN1_TIME* last = X509_CRL_get0_lastUpdate(crl);
  return (!next || X509_cmp_current_time(next) > 0) && (!last || X509_cmp_current_time(last) <= 0);
}

// OpenSSL checks a client certificate against a CRL of its issuer, the best
// it has: a CA with one current CRL in the file is fine, whatever older ones
// lie beside it. Only a CA none of whose CRLs is current refuses its clients.
void crl_dates(const std::string& path, std::vector<std::string>& out) {
  if (path.empty()) return;
  Bio in(BIO_new_file(path.c_str(), "r"));
  if (!in) return;
  std::vector<Crl> crls;
  while (Crl crl{PEM_read_bio_X509_CRL(in.get(), nullptr, nullptr, nullptr)}) crls.push_back(std::move(crl));
  ERR_clear_error();  // the end of the file reads as "no start line"
  for (std::size_t i = 0; i < crls.size(); ++i) {
    const X509_NAME* issuer = X509_CRL_get_issuer(crls[i].get());
    bool seen_before = false, any_current = false;
    const X509_CRL* latest = crls[i].get();
    for (std::size_t j = 0; j < crls.size(); ++j) {
      if (X509_NAME_cmp(issuer, X509_CRL_get_issuer(crls[j].get())) != 0) continue;
      if (j < i) seen_before = true;
      any_current = any_current || current(crls[j].get());
      const ASN1_TIME* a = X509_CRL_get0_nextUpdate(latest);
      const ASN1_TIME* b = X509_CRL_get0_nextUpdate(crls[j].get());
      if (a && b && ASN1_TIME_compare(b, a) > 0) latest = crls[j].get();
    }
    if (seen_before || any_current) continue;
    const std::string who = name_text(issuer);
    const ASN1_TIME* next = X509_CRL_get0_nextUpdate(latest);
    if (next && X509_cmp_current_time(next) <= 0)
      out.push_back("CRL " + path + " of " + who + " expired at " + time_text(next) +
                    " (its next update): every client certificate that CA issued is refused with \"CRL has "
                    "expired\" until a current CRL from it is installed there (then SIGHUP or restart)");
    else
      out.push_back("CRL " + path + " of " + who + " is not valid before " +
                    time_text(X509_CRL_get0_lastUpdate(latest)) +
                    ": every client certificate that CA issued is refused until then; check this machine's clock");
  }
}

}  // namespace

std::vector<std::string> server_file_warnings(const ServerFiles& files) {
  std::vector<std::string> out;
  key_mode(files.key, out);
  crl_dates(files.crl, out);
  return out;
}

}  // namespace tls
