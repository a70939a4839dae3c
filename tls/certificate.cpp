#include "tls/certificate.hpp"

#include <openssl/asn1.h>
#include <openssl/bio.h>
#include <openssl/objects.h>

#include <ctime>

#include "tls/handles.hpp"

namespace tls {
namespace {

std::string bio_text(BIO* bio) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio, &data);
  return n > 0 ? std::string(data, static_cast<std::size_t>(n)) : std::string();
}

}  // namespace

std::string time_text(const ASN1_TIME* t) {
  std::tm tm{};
  if (!t || ASN1_TIME_to_tm(t, &tm) != 1) return "?";
  char out[32];
  std::strftime(out, sizeof out, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return out;
}

std::string subject_of(const X509* cert) {
  const X509_NAME* name = cert ? X509_get_subject_name(cert) : nullptr;
  if (!name) return "?";
  Bio bio(BIO_new(BIO_s_mem()));
  if (!bio || X509_NAME_print_ex(bio.get(), name, 0, XN_FLAG_RFC2253) < 0) return "?";
  std::string text = bio_text(bio.get());
  return text.empty() ? "?" : text;
}

std::expected<std::optional<std::string>, std::string> role_of(const X509* cert) {
  const Asn1Object oid(OBJ_txt2obj(kRoleOid, 1));
  if (!oid) return std::unexpected(std::string("cannot make the role OID ") + kRoleOid);
  const int at = X509_get_ext_by_OBJ(cert, oid.get(), -1);
  if (at < 0) return std::nullopt;
  const ASN1_OCTET_STRING* value = X509_EXTENSION_get_data(X509_get_ext(cert, at));
  const unsigned char* p = ASN1_STRING_get0_data(value);
  const long length = ASN1_STRING_length(value);
  const Utf8String role(d2i_ASN1_UTF8STRING(nullptr, &p, length));
  if (!role || p != ASN1_STRING_get0_data(value) + length)
    return std::unexpected(std::string("the role extension ") + kRoleOid + " is not an ASN.1 UTF8String");
  return std::string(reinterpret_cast<const char*>(ASN1_STRING_get0_data(role.get())),
                     static_cast<std::size_t>(ASN1_STRING_length(role.get())));
}

std::string not_after_text(const X509* cert) { return time_text(X509_get0_notAfter(cert)); }
std::string not_before_text(const X509* cert) { return time_text(X509_get0_notBefore(cert)); }

}  // namespace tls
