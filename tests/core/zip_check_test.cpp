#include "core/zip_check.h"

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "test_support.h"

namespace fs = std::filesystem;
using uavsim::testing::ConfigErrorOf;

TEST_CASE("ZipCheck: a .pt file cut short is refused as truncated, a whole one passes", "[core]") {
  // Issue 43: a truncated radar.pt gave LibTorch's "PytorchStreamReader
  // failed reading zip archive: failed finding central directory".
  const std::string shipped = std::string(UAVSIM_SOURCE_DIR) + "/models/default/radar.pt";
  CHECK(ConfigErrorOf([&] { uavsim::core::RequireWholeZip(shipped); }).empty());
  const std::string dir = uavsim::testing::TempDir("zip-check");
  const std::string cut = dir + "/radar.pt";
  fs::copy_file(shipped, cut);
  const auto size = fs::file_size(cut);
  for (const auto n : {size - 1, size / 2, std::uintmax_t{30}}) {
    fs::resize_file(cut, n);
    INFO(n << " of " << size << " bytes");
    CHECK(ConfigErrorOf([&] { uavsim::core::RequireWholeZip(cut); }) ==
          cut + ": truncated: its " + std::to_string(n) +
              " bytes end before the zip archive a .pt file is does (cut short while written or "
              "copied?)");
  }
  // Not a zip archive at all: left to the loader, which says what it is not.
  uavsim::testing::WriteFile(dir + "/text.pt", "not a model\n");
  CHECK(ConfigErrorOf([&] { uavsim::core::RequireWholeZip(dir + "/text.pt"); }).empty());
}
