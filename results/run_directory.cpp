#include "results/run_directory.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/interrupt.h"

namespace uavsim::results {
namespace fs = std::filesystem;

bool ProcessAlive(pid_t pid) {
  if (pid <= 0) return false;  // no process's number (kill() would take it as a group)
  if (::kill(pid, 0) != 0 && errno == ESRCH) return false;
  // kill() also finds a process that has ended but is not yet reaped (a
  // zombie, while its parent has not waited for it; 'X' while it is being
  // reaped): it runs nothing and writes nothing, so what it left is stale.
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) {
    std::error_code ec;  // gone since kill(), unless there is no /proc to read
    return !fs::exists("/proc/self/stat", ec);
  }
  const auto paren = line.rfind(')');
  if (paren == std::string::npos || paren + 2 >= line.size()) return true;
  const char state = line[paren + 2];
  return state != 'Z' && state != 'X' && state != 'x';
}

std::optional<pid_t> StagingOwner(const std::string& folder_name, std::string* final_name) {
  const auto at = folder_name.rfind(".partial-");
  if (folder_name.size() < 2 || folder_name[0] != '.' || at == std::string::npos || at < 2)
    return std::nullopt;
  // ".NAME.partial-PID", or ".NAME.partial-PID.old" (a replaced run's
  // remains while Commit swaps it out).
  std::string digits = folder_name.substr(at + 9);
  const auto end = digits.find_first_not_of("0123456789");
  if (end != std::string::npos) {
    if (digits.substr(end) != ".old") return std::nullopt;
    digits.resize(end);
  }
  if (digits.empty() || digits.size() > 9) return std::nullopt;
  if (final_name) *final_name = folder_name.substr(1, at - 1);
  return static_cast<pid_t>(std::stol(digits));
}

std::size_t RemoveStaleStaging(const std::string& final_dir) {
  const fs::path final_path(final_dir);
  fs::path parent = final_path.parent_path();
  if (parent.empty()) parent = ".";
  std::size_t removed = 0;
  std::error_code ec;
  // Any name's: a run killed as `--out k` leaves `.k.partial-PID`, which a
  // later command of another name in the same folder clears (issue 43).
  for (const auto& e : fs::directory_iterator(parent, ec)) {
    const auto pid = StagingOwner(e.path().filename().string(), nullptr);
    if (!pid || *pid == ::getpid() || ProcessAlive(*pid)) continue;
    std::error_code rm;
    if (fs::remove_all(e.path(), rm) > 0 && !rm) ++removed;
  }
  return removed;
}

std::size_t RemoveStaleTemporaries(const std::string& folder) {
  std::size_t removed = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    const std::string name = e.path().filename().string();
    const auto at = name.rfind(".tmp-");
    if (at == std::string::npos || at == 0) continue;
    const std::string digits = name.substr(at + 5);
    if (digits.empty() || digits.size() > 9 ||
        digits.find_first_not_of("0123456789") != std::string::npos)
      continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (pid == ::getpid() || ProcessAlive(pid) || !e.is_regular_file(ec)) continue;
    std::error_code rm;
    if (fs::remove(e.path(), rm) && !rm) ++removed;
  }
  return removed;
}

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
  RemoveStaleStaging(final_dir_);
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
  // A termination request during the last writes: nothing goes in place.
  core::ThrowIfInterrupted();
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
