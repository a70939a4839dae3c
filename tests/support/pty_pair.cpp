#include "tests/support/pty_pair.hpp"

#include <signal.h>

#include <sstream>
#include <stdexcept>

#include "tests/support/process.hpp"
#include "tests/support/wait.hpp"

namespace test_support {

using namespace std::chrono_literals;

PtyPair::PtyPair() {
  if (!program_exists("socat")) throw std::runtime_error("socat is not installed (tools/install-deps.sh)");
  log_ = dir_.file("socat.log");
  pid_ = spawn({"socat", "-d", "-d", "pty,raw,echo=0", "pty,raw,echo=0"}, Output::null(), Output::file(log_)).pid;
  // "... N PTY is /dev/pts/5" twice, then "starting data transfer loop".
  const bool ok = wait_until(
      [&] {
        ends_.clear();
        std::istringstream in(read_file(log_));
        std::string line;
        bool started = false;
        while (std::getline(in, line)) {
          if (auto at = line.find("PTY is "); at != std::string::npos) ends_.push_back(line.substr(at + 7));
          if (line.find("starting data transfer loop") != std::string::npos) started = true;
        }
        return ends_.size() == 2 && started;
      },
      5s);
  if (!ok) {
    (void)end_process(pid_, SIGTERM, 2s);
    pid_ = -1;
    throw std::runtime_error("socat gave no pty pair: " + read_file(log_));
  }
}

PtyPair::~PtyPair() {
  if (pid_ > 0) (void)end_process(pid_, SIGTERM, 3s);
}

}  // namespace test_support
