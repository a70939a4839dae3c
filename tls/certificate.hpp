#pragma once
// What the module reads from a client's certificate: who it is (the subject)
// and its Modbus/TCP Security role, carried in a private extension.
#include <openssl/x509.h>

#include <expected>
#include <optional>
#include <string>

namespace tls {

// The role extension of the Modbus/TCP Security protocol: an ASN.1
// UTF8String. In an openssl extension file:
//   1.3.6.1.4.1.50316.802.1 = ASN1:UTF8String:operator
inline constexpr const char* kRoleOid = "1.3.6.1.4.1.50316.802.1";

// "CN=line3-hmi,O=Plant" (RFC 2253, most specific first); "?" without a name.
std::string subject_of(const X509* cert);

// The role the certificate carries; nullopt when it has no role extension;
// an error when the extension is there but is not a UTF8String.
std::expected<std::optional<std::string>, std::string> role_of(const X509* cert);

// "2031-05-01 12:00:00 UTC": when the certificate stops (not_after) or starts
// (not_before) being valid.
std::string not_after_text(const X509* cert);
// "2026-11-29 14:32:00 UTC", "?" when unreadable.
std::string time_text(const ASN1_TIME* t);
std::string not_before_text(const X509* cert);

}  // namespace tls
