#include "pipeline/model_checksums.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/sha256.h"

namespace uavsim::pipeline {
namespace fs = std::filesystem;

void WriteModelChecksums(const std::string& folder) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(folder))
    if (e.is_regular_file() && e.path().filename() != kModelChecksumsFile)
      names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  std::string text;
  for (const std::string& name : names)
    text += core::Sha256FileHex((fs::path(folder) / name).string()) + "  " + name + "\n";
  core::WriteFileAtomic((fs::path(folder) / kModelChecksumsFile).string(), text);
}

void VerifyModelChecksums(const std::string& folder) {
  const fs::path sums = fs::path(folder) / kModelChecksumsFile;
  std::error_code ec;
  if (!fs::exists(sums, ec)) return;
  std::istringstream in(core::ReadFileBytes(sums.string()));
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    const std::string at = "line " + std::to_string(number);
    // "<64 hex>  <name>" (two spaces: sha256sum's text mode; '*' binary).
    if (line.size() < 67 || line[64] != ' ' || (line[65] != ' ' && line[65] != '*') ||
        line.find_first_not_of("0123456789abcdef") < 64)
      throw core::ConfigError(sums.string(), "",
                              at + ": expected \"<64 hex digits>  <file name>\"");
    const std::string expected = line.substr(0, 64), name = line.substr(66);
    if (name.find('/') != std::string::npos || name == "." || name == "..")
      throw core::ConfigError(sums.string(), "",
                              at + ": \"" + name + "\" is not a file of the folder");
    const fs::path file = fs::path(folder) / name;
    if (!fs::is_regular_file(file, ec))
      throw core::ConfigError(sums.string(), "", at + ": " + name + " is missing");
    const std::string got = core::Sha256FileHex(file.string());
    if (got != expected)
      throw core::ConfigError(sums.string(), "",
                              name +
                                  " has changed or is corrupted since the model was written: "
                                  "its SHA-256 is " +
                                  got + ", the model lists " + expected +
                                  " (retrain it, or restore the file)");
  }
}

}  // namespace uavsim::pipeline
