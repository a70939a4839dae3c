// server::DatabaseLock: one homingd per settings database (server/database_lock.hpp).
#include <catch2/catch.hpp>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "server/database_lock.hpp"
#include "tests/support/temp_dir.hpp"

TEST_CASE("a database locked by one holder is refused to the next naming the holder's pid until it lets go") {
  test_support::TempDir dir{"db-lock-test"};
  const std::string db = dir.file("machine.db");
  std::optional<server::DatabaseLock> first;
  {
    auto taken = server::DatabaseLock::take(db);
    REQUIRE(taken);
    first.emplace(std::move(*taken));
  }
  CHECK(std::filesystem::exists(db + ".lock"));
  const auto second = server::DatabaseLock::take(db);
  REQUIRE_FALSE(second);
  CHECK(second.error() == "--db " + db + ": another homingd uses this database (pid " + std::to_string(::getpid()) +
                              "); stop it first (systemctl stop homingd), or give this one its own --db");
  first.reset();  // the holder ends
  CHECK(server::DatabaseLock::take(db));
}

TEST_CASE("a database lock in a directory that does not exist is refused naming the lock file and the fix") {
  test_support::TempDir dir{"db-lock-test"};
  const std::string db = dir.file("no-such-dir/machine.db");
  const auto lock = server::DatabaseLock::take(db);
  REQUIRE_FALSE(lock);
  CHECK_THAT(lock.error(), Catch::Contains("cannot open its lock file " + db + ".lock") &&
                               Catch::Contains("check that the directory exists"));
}

TEST_CASE("a database reached through a symbolic link is the same database: its lock refuses the second holder") {
  test_support::TempDir dir{"db-lock-test"};
  const std::string db = dir.file("machine.db");
  const std::string alias = dir.file("alias.db");
  std::ofstream(db) << "";  // the running daemon's database
  std::filesystem::create_symlink(db, alias);
  auto first = server::DatabaseLock::take(db);
  REQUIRE(first);
  const auto second = server::DatabaseLock::take(alias);
  REQUIRE_FALSE(second);
  CHECK_THAT(second.error(), Catch::Contains("another homingd uses this database"));
}
