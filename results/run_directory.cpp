#include "results/run_directory.h"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>

namespace uavsim::results {
namespace fs = std::filesystem;

RunDirectory::RunDirectory(std::string final_dir, bool force)
    : final_dir_(std::move(final_dir)), force_(force) {
  while (final_dir_.size() > 1 && final_dir_.back() == '/') final_dir_.pop_back();
  const fs::path final_path(final_dir_);
  std::error_code ec;
  if (fs::exists(final_path, ec) && !force_)
    throw core::UsageError(final_dir_ +
                           ": already exists; choose another --out or pass --force to replace it");
  fs::path parent = final_path.parent_path();
  if (parent.empty()) parent = ".";
  fs::create_directories(parent, ec);
  if (ec) throw std::runtime_error(parent.string() + ": cannot create folder: " + ec.message());
  staging_dir_ =
      (parent / ("." + final_path.filename().string() + ".partial-" + std::to_string(::getpid())))
          .string();
  fs::remove_all(staging_dir_, ec);
  fs::create_directory(staging_dir_, ec);
  if (ec) throw std::runtime_error(staging_dir_ + ": cannot create folder: " + ec.message());
}

RunDirectory::~RunDirectory() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(staging_dir_, ec);
  }
}

std::string RunDirectory::StagingPath(const std::string& relative_path) {
  const fs::path p = fs::path(staging_dir_) / relative_path;
  std::error_code ec;
  fs::create_directories(p.parent_path(), ec);
  if (ec)
    throw std::runtime_error(p.parent_path().string() + ": cannot create folder: " + ec.message());
  return p.string();
}

void RunDirectory::WriteText(const std::string& relative_path, const std::string& content) {
  WriteFileAtomic(StagingPath(relative_path), content);
}

void RunDirectory::WriteJson(const std::string& relative_path, const core::Json& json) {
  WriteText(relative_path, json.dump(2) + "\n");
}

void RunDirectory::Commit() {
  std::error_code ec;
  const fs::path final_path(final_dir_);
  std::string trash;
  if (fs::exists(final_path, ec)) {
    if (!force_)
      throw core::UsageError(final_dir_ + ": appeared while the run was going; not replaced");
    trash = staging_dir_ + ".old";
    fs::rename(final_path, trash, ec);
    if (ec) throw std::runtime_error(final_dir_ + ": cannot replace: " + ec.message());
  }
  fs::rename(staging_dir_, final_path, ec);
  if (ec)
    throw std::runtime_error(final_dir_ + ": cannot move the run into place: " + ec.message());
  committed_ = true;
  if (!trash.empty()) fs::remove_all(trash, ec);
}

}  // namespace uavsim::results
