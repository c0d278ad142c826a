#include "results/run_directory.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "results/csv.h"
#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::results::RunDirectory;

TEST_CASE("RunDirectory: nothing appears under the final name until Commit", "[results]") {
  const std::string root = uavsim::testing::TempDir("rundir");
  const std::string final_dir = root + "/run1";
  {
    RunDirectory dir(final_dir, false);
    dir.WriteText("truth.csv", "t_s\n");
    dir.WriteText("frames/lidar/000000.ply", "ply\n");
    CHECK_FALSE(fs::exists(final_dir));
    // Abandoned without Commit (a failed run): staging is removed too.
  }
  CHECK_FALSE(fs::exists(final_dir));
  CHECK(fs::is_empty(root));

  {
    RunDirectory dir(final_dir, false);
    dir.WriteText("truth.csv", "t_s\n1\n");
    dir.Commit();
  }
  CHECK(uavsim::testing::ReadFile(final_dir + "/truth.csv") == "t_s\n1\n");
  CHECK_THROWS_AS(RunDirectory(final_dir, false), uavsim::core::UsageError);

  {
    RunDirectory dir(final_dir, true);
    dir.WriteText("metrics.json", "{}\n");
    dir.Commit();
  }
  CHECK(fs::exists(final_dir + "/metrics.json"));
  CHECK_FALSE(fs::exists(final_dir + "/truth.csv"));  // replaced whole, not merged
  // Only the final folder remains: no temp files, no staging.
  int entries = 0;
  for (auto& e : fs::directory_iterator(root)) ++entries, (void)e;
  CHECK(entries == 1);
}

TEST_CASE("WriteFileAtomic: replaces content and leaves no temp file", "[results]") {
  const std::string root = uavsim::testing::TempDir("atomic");
  uavsim::results::WriteFileAtomic(root + "/a.txt", "one");
  uavsim::results::WriteFileAtomic(root + "/a.txt", "two");
  CHECK(uavsim::testing::ReadFile(root + "/a.txt") == "two");
  int entries = 0;
  for (auto& e : fs::directory_iterator(root)) ++entries, (void)e;
  CHECK(entries == 1);
  CHECK_THROWS_WITH(uavsim::results::WriteFileAtomic(root + "/no/such/dir/a.txt", "x"),
                    Catch::Contains("cannot create"));
}

TEST_CASE("CsvTable: fixed formatting without negative zero", "[results]") {
  uavsim::results::CsvTable t({"a", "b"});
  t.AddRow({uavsim::results::FormatFixed(-0.0000001, 3), uavsim::results::FormatFixed(2.5, 2)});
  CHECK(t.str() == "a,b\n0.000,2.50\n");
  CHECK(t.rows() == 1);
  CHECK_THROWS(t.AddRow({"1"}));
}

TEST_CASE("RunDirectory: staging folders of dead processes are removed, live ones kept",
          "[results]") {
  // What a run or a training killed with SIGKILL leaves: ".NAME.partial-PID"
  // (issue 24: no later command removed them).
  const std::string dir = uavsim::testing::TempDir("stale");
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);  // now a PID of no live process
  const std::string dead = dir + "/.run.partial-" + std::to_string(child);
  const std::string dead_old = dir + "/.run.partial-" + std::to_string(child) + ".old";
  const std::string live = dir + "/.run.partial-" + std::to_string(getppid());
  const std::string other = dir + "/.other.partial-" + std::to_string(child);
  for (const auto& d : {dead, dead_old, live, other}) fs::create_directories(d + "/sub");
  CHECK(uavsim::results::ProcessAlive(getppid()));
  CHECK_FALSE(uavsim::results::ProcessAlive(child));
  std::string name;
  CHECK(uavsim::results::StagingOwner(".run.partial-42", &name) == 42);
  CHECK(name == "run");
  CHECK(uavsim::results::StagingOwner(".run.partial-42.old", &name) == 42);
  CHECK_FALSE(uavsim::results::StagingOwner("run.partial-42", &name));
  CHECK_FALSE(uavsim::results::StagingOwner(".run.partial-", &name));
  CHECK_FALSE(uavsim::results::StagingOwner(".run.partial-4x", &name));
  {
    RunDirectory run(dir + "/run", false);
    CHECK_FALSE(fs::exists(dead));
    CHECK_FALSE(fs::exists(dead_old));
    CHECK(fs::exists(live));  // its process is alive: maybe another run in the making
    // Another name's too (issue 43: a killed `run --out k` left `.k.partial-PID`
    // until a later run named k).
    CHECK_FALSE(fs::exists(other));
  }
  fs::create_directories(other);
  CHECK(uavsim::results::RemoveStaleStaging(dir + "/third") == 1);
  CHECK_FALSE(fs::exists(other));
  CHECK(fs::exists(live));
}

TEST_CASE("RunDirectory: a zombie's staging folder and temporaries are stale at once",
          "[results]") {
  // A process killed a moment ago stays a zombie until its parent waits for
  // it (a shell, a scheduler or a Python parent may take seconds): it runs
  // nothing and writes nothing, so the next command removes what it left.
  const std::string dir = uavsim::testing::TempDir("zombie");
  const pid_t child = fork();
  if (child == 0) _exit(0);
  // Until its /proc entry says it has ended (not reaped: kill() still finds it).
  const auto state = [child] {
    std::ifstream stat("/proc/" + std::to_string(child) + "/stat");
    std::string line;
    std::getline(stat, line);
    const auto paren = line.rfind(')');
    return paren == std::string::npos || paren + 2 >= line.size() ? '?' : line[paren + 2];
  };
  for (int i = 0; i < 500 && state() != 'Z'; ++i) usleep(2000);
  REQUIRE(state() == 'Z');
  CHECK(kill(child, 0) == 0);
  CHECK_FALSE(uavsim::results::ProcessAlive(child));
  CHECK_FALSE(uavsim::results::ProcessAlive(0));  // not a process's number
  CHECK_FALSE(uavsim::results::ProcessAlive(-1));
  const std::string staged = dir + "/.run.partial-" + std::to_string(child);
  const std::string temporary = dir + "/x.csv.tmp-" + std::to_string(child);
  fs::create_directories(staged + "/sub");
  uavsim::testing::WriteFile(temporary, "half");
  {
    RunDirectory run(dir + "/run", false);
    CHECK_FALSE(fs::exists(staged));
  }
  CHECK(uavsim::results::RemoveStaleTemporaries(dir) == 1);
  CHECK_FALSE(fs::exists(temporary));
  int status = 0;
  waitpid(child, &status, 0);
}

TEST_CASE("RemoveStaleTemporaries: the temporary files of dead processes go, the rest stay",
          "[results]") {
  // What WriteFileAtomic (".NAME.tmp-PID"), WriteViaTemporary and the episode
  // writer ("NAME.tmp-PID") leave when killed with SIGKILL (issue 24).
  const std::string dir = uavsim::testing::TempDir("stale-tmp");
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  const std::string dead = std::to_string(child);
  const std::vector<std::string> gone = {"pre.eps.tmp-" + dead, ".claims.csv.tmp-" + dead};
  const std::vector<std::string> kept = {"pre.eps.tmp-" + std::to_string(getppid()),  // alive
                                         "pre.eps.tmp-" + std::to_string(getpid()),   // ours
                                         "pre.eps.tmp-12x", "pre.eps", ".tmp-" + dead};
  for (const auto& f : gone) uavsim::testing::WriteFile(dir + "/" + f, "x");
  for (const auto& f : kept) uavsim::testing::WriteFile(dir + "/" + f, "x");
  fs::create_directories(dir + "/folder.tmp-" + dead);  // not a file: kept
  CHECK(uavsim::results::RemoveStaleTemporaries(dir) == 2);
  for (const auto& f : gone) CHECK_FALSE(fs::exists(dir + "/" + f));
  for (const auto& f : kept) CHECK(fs::exists(dir + "/" + f));
  CHECK(fs::exists(dir + "/folder.tmp-" + dead));
}
