#pragma once
// OpenSSL reports why a call failed in a per-thread queue of errors.
#include <string>
#include <string_view>

namespace tls {

// The queue's reasons as one line ("; " between them), and the queue emptied;
// `fallback` when it was empty.
std::string take_errors(std::string_view fallback = "unknown OpenSSL error");

}  // namespace tls
