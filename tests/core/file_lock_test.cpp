#include "core/file_lock.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <optional>
#include <string>

#include "core/error.h"
#include "core/interrupt.h"
#include "test_support.h"

using uavsim::core::FileLock;

TEST_CASE("FileLock: a second holder is refused naming the first, or waits", "[core]") {
  // Issue 43: two sweeps with one --out ran the same points. flock(2) locks
  // conflict between open files even in one process, so one test process
  // plays both commands.
  const std::string path = uavsim::testing::TempDir("file-lock") + "/.lock";
  std::optional<FileLock> first;
  first.emplace(path, "uavsim sweep: out", false);
  CHECK_THAT(uavsim::testing::ReadFile(path),
             Catch::StartsWith(std::to_string(::getpid()) + " " + uavsim::core::OwnCommandLine()));
  std::string refused;
  try {
    FileLock second(path, "uavsim sweep: out", false);
  } catch (const uavsim::core::UsageError& e) {
    refused = e.what();
  }
  CHECK(refused == "uavsim sweep: out: in use by process " + std::to_string(::getpid()) + " (" +
                       uavsim::core::OwnCommandLine() + ") (lock " + path +
                       "); pass --wait to wait for it");
  // Waiting, it still answers a termination request.
  uavsim::core::RequestInterrupt();
  CHECK_THROWS_AS(FileLock(path, "uavsim sweep: out", true), uavsim::core::Interrupted);
  uavsim::core::ClearInterrupt();
  first.reset();  // released, and its file removed: the next one takes a new one
  CHECK_FALSE(std::filesystem::exists(path));
  {
    const FileLock next(path, "uavsim sweep: out", false);
    CHECK(std::filesystem::exists(path));
  }
  CHECK_FALSE(std::filesystem::exists(path));
}
