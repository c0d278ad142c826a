#include "core/atomic_file.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::testing::ReadFile;
using uavsim::testing::TempDir;

namespace {
std::size_t Entries(const std::string& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), {}));
}
}  // namespace

TEST_CASE("WriteViaTemporary: the file appears only when the writer succeeds", "[core]") {
  const std::string dir = TempDir("atomic");
  const std::string path = dir + "/weights.pt";
  uavsim::core::WriteFileAtomic(path, "old");
  // A writer that fails half-way: the old file stays, no temporary is left.
  CHECK_THROWS_AS(uavsim::core::WriteViaTemporary(path,
                                                  [](const std::string& temp) {
                                                    std::ofstream(temp) << "half";
                                                    throw std::logic_error("disk full");
                                                  }),
                  std::logic_error);
  CHECK(ReadFile(path) == "old");
  CHECK(Entries(dir) == 1);
  // A writer that succeeds: its file, under the final name, nothing else.
  std::string temp_seen;
  uavsim::core::WriteViaTemporary(path, [&](const std::string& temp) {
    temp_seen = temp;
    std::ofstream(temp) << "new";
  });
  CHECK(ReadFile(path) == "new");
  CHECK(fs::path(temp_seen).parent_path() == fs::path(path).parent_path());  // same file system
  CHECK(temp_seen != path);
  CHECK(Entries(dir) == 1);
  // A writer that writes nothing: the rename fails, naming the path.
  CHECK_THROWS_WITH(uavsim::core::WriteViaTemporary(path, [](const std::string&) {}),
                    Catch::Contains(path));
  CHECK(ReadFile(path) == "new");
}
