#include "apps/sweep/recorded_folder.h"

#include <filesystem>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/error.h"

namespace uavsim::sim {

namespace fs = std::filesystem;

std::optional<core::Json> ReadFolderRecord(const std::string& dir, const std::string& name) {
  const fs::path file = fs::path(dir) / name;
  std::error_code ec;
  if (!fs::exists(file, ec)) return std::nullopt;
  try {
    return core::Json::parse(core::ReadFileBytes(file.string()));
  } catch (const core::Json::exception& e) {
    throw core::UsageError(file.string() + ": unreadable (" + e.what() + "); remove " + dir +
                           " or choose another --out");
  }
}

void CreateRecordedFolder(const std::string& dir, const std::string& name, const core::Json& record,
                          const std::vector<std::string>& subfolders) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  for (const std::string& sub : subfolders) fs::create_directories(fs::path(dir) / sub, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create folder: " + ec.message());
  core::WriteFileAtomic((fs::path(dir) / name).string(), record.dump(2) + "\n");
}

}  // namespace uavsim::sim
