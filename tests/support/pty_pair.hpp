#pragma once
// Two linked pseudo-terminals (socat -d -d pty,raw,echo=0 pty,raw,echo=0), for
// RTU tests without a serial port; socat is stopped by PID when the pair goes.
#include <sys/types.h>

#include <string>
#include <vector>

#include "tests/support/temp_dir.hpp"

namespace test_support {

class PtyPair {
 public:
  PtyPair();  // throws when socat is missing or gives no pair within 5 s
  ~PtyPair();
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;
  const std::string& server_end() const { return ends_[0]; }
  const std::string& client_end() const { return ends_[1]; }

 private:
  TempDir dir_{"socat"};
  std::string log_;
  pid_t pid_ = -1;
  std::vector<std::string> ends_;
};

}  // namespace test_support
