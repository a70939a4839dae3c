// The check every end-to-end test makes when it is done with its homingd
// (e2e::Daemon's destructor): a test_support::Homingd here, so that the
// problems it finds are looked at rather than failing this test.
#include <catch2/catch.hpp>

#include "daemon.hpp"

using namespace e2e;

namespace {

// A homingd with problems keeps its directory for a post-mortem: not this one's.
void remove_files(const Homingd& d) { std::filesystem::remove_all(std::filesystem::path(d.log_path()).parent_path()); }

}  // namespace

TEST_CASE("the end-of-test check passes a homingd that exits 0 on SIGTERM") {
  Homingd d(DaemonOptions{.program = homingd_path()});
  CHECK(d.shutdown_problems().empty());
  CHECK_FALSE(d.running());
}

TEST_CASE("the end-of-test check names a homingd that did not exit 0") {
  Homingd d(DaemonOptions{.program = homingd_path()});
  // SIGUSR2 is not one homingd handles: it ends it as a crash would.
  REQUIRE(::kill(d.pid(), SIGUSR2) == 0);
  const std::string problems = d.shutdown_problems();
  remove_files(d);
  CHECK_THAT(problems, Catch::Contains("ended by signal " + std::to_string(SIGUSR2)) &&
                           Catch::Contains("not a clean exit 0") && Catch::Contains("--- homingd log"));
}

TEST_CASE("the end-of-test check names each sanitizer report in homingd's stderr") {
  Homingd d(DaemonOptions{.program = homingd_path()});
  // As ASan and UBSan write them to homingd's stderr, which is the log.
  std::ofstream(d.log_path(), std::ios::app)
      << "==4242==ERROR: AddressSanitizer: heap-use-after-free on address 0x602000000010\n"
      << "    #0 0x55 in server::TcpServer::drop(int) server/tcp_server.cpp:120\n"
      << "server/pdu.cpp:42:17: runtime error: signed integer overflow\n";
  CHECK(sanitizer_reports(d.log()).size() == 2);  // the stack line is not a report of its own
  const std::string problems = d.shutdown_problems();
  remove_files(d);
  CHECK_THAT(problems, Catch::Contains("sanitizer report in homingd's stderr: ==4242==ERROR: AddressSanitizer") &&
                           Catch::Contains("sanitizer report in homingd's stderr: server/pdu.cpp:42:17: runtime error"));
  CHECK_THAT(problems, !Catch::Contains("not a clean exit"));  // it did exit 0
}

TEST_CASE("a homingd the test kills on purpose is not held to exit 0, its sanitizer reports still count") {
  Homingd d(DaemonOptions{.program = homingd_path()});
  REQUIRE(d.stop(SIGKILL, 5s));
  CHECK(d.shutdown_problems().empty());
  std::ofstream(d.log_path(), std::ios::app) << "SUMMARY: UndefinedBehaviorSanitizer: undefined-behavior x.cpp:1:1\n";
  const std::string problems = d.shutdown_problems();
  remove_files(d);
  CHECK_THAT(problems, Catch::Contains("SUMMARY: UndefinedBehaviorSanitizer"));
}
