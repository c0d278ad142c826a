// A run's output directory, written all-or-nothing. Files go into a hidden
// staging directory beside the final one, each written to a temporary name
// and renamed; Commit() renames the staging directory to its final name.
// A run that throws or is killed never leaves its final directory behind
// half-written (a killed run leaves only the hidden ".NAME.partial-PID",
// which the next RunDirectory in the same folder removes once process PID
// is gone).
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>

#include "core/atomic_file.h"
#include "core/json_io.h"

namespace uavsim::results {

// Writes `content` to `path` atomically (core/atomic_file.h).
using core::WriteFileAtomic;

// Whether `pid` is a live process of this host (a zombie is not).
bool ProcessAlive(pid_t pid);

// The process that made the staging folder named `folder_name`
// (".NAME.partial-PID", or ".NAME.partial-PID.old" while Commit replaces an
// old run), and NAME in *final_name; nothing for other names.
std::optional<pid_t> StagingOwner(const std::string& folder_name, std::string* final_name);

// Removes the staging folders ".NAME.partial-PID" beside `final_dir`, of
// any NAME, whose process is gone: what a run, a training or a sweep point
// killed with SIGKILL left. Returns how many.
std::size_t RemoveStaleStaging(const std::string& final_dir);

// Removes the files "<name>.tmp-PID" and ".<name>.tmp-PID" in `folder`
// (what WriteFileAtomic, WriteViaTemporary and the episode writer leave
// when killed) whose process is gone. Returns how many.
std::size_t RemoveStaleTemporaries(const std::string& folder);

class RunDirectory {
 public:
  // Throws core::UsageError if `final_dir` exists and `force` is false.
  // Removes the stale staging folders beside it first, of any name
  // (RemoveStaleStaging).
  RunDirectory(std::string final_dir, bool force);
  ~RunDirectory();  // removes the staging directory unless committed
  RunDirectory(const RunDirectory&) = delete;
  RunDirectory& operator=(const RunDirectory&) = delete;

  // `relative_path` may contain folders; they are created.
  void WriteText(const std::string& relative_path, const std::string& content);
  void WriteJson(const std::string& relative_path, const core::Json& json);
  // Where a writer that streams its own file should put `relative_path`
  // (inside staging; folders created).
  std::string StagingPath(const std::string& relative_path);

  // Moves staging to the final name (replacing an old run if `force`).
  // Throws core::Interrupted, moving nothing, once a termination request
  // has arrived (core/interrupt.h).
  void Commit();

  const std::string& final_dir() const { return final_dir_; }

 private:
  std::string final_dir_;
  std::string staging_dir_;
  bool force_;
  bool committed_ = false;
};

}  // namespace uavsim::results
