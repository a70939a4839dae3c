#pragma once
// Loopback ports for servers a test starts.

namespace test_support {

// A 127.0.0.1 port that was free a moment ago (bind to port 0, read it,
// close): whoever uses it must retry if another process took it first.
int free_port();

}  // namespace test_support
