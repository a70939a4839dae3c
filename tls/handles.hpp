#pragma once
// RAII for the OpenSSL objects the project holds: each one freed by its own
// function when its owner goes.
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include <memory>

namespace tls {

template <auto Free>
struct FreeWith {
  template <typename T>
  void operator()(T* p) const {
    Free(p);
  }
};

using SslCtx = std::unique_ptr<SSL_CTX, FreeWith<&SSL_CTX_free>>;
using Ssl = std::unique_ptr<SSL, FreeWith<&SSL_free>>;
using Bio = std::unique_ptr<BIO, FreeWith<&BIO_free_all>>;
using Crl = std::unique_ptr<X509_CRL, FreeWith<&X509_CRL_free>>;
using Asn1Object = std::unique_ptr<ASN1_OBJECT, FreeWith<&ASN1_OBJECT_free>>;
using Utf8String = std::unique_ptr<ASN1_UTF8STRING, FreeWith<&ASN1_UTF8STRING_free>>;

}  // namespace tls
