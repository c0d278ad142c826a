// An exclusive advisory lock (flock(2)) on a file, held while the object
// lives, so that two commands do not write the same output at once (two
// sweeps with one --out, two trainings extending one episode file). The
// holder writes its process id and command line into the file; a command
// that finds the lock taken names them. The lock goes with the process
// (a killed holder releases it); the holder removes the file as it lets
// go (a killed one leaves it, unlocked, for the next holder to remove).
#pragma once

#include <string>

namespace uavsim::core {

class FileLock {
 public:
  // Takes the lock on `path` (created if missing; its folder must exist).
  // When another process holds it: with `wait` false, throws
  // core::UsageError "WHAT: in use by process PID (COMMAND); ... pass
  // --wait to wait for it"; with `wait` true, waits for it, polling for
  // termination requests (throws core::Interrupted). Throws
  // std::runtime_error if the file cannot be opened.
  FileLock(const std::string& path, const std::string& what, bool wait);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  bool TakeOnce(const std::string& what, bool wait);
  std::string path_;
  int fd_ = -1;
};

// This process's command line, its arguments separated by spaces.
std::string OwnCommandLine();

}  // namespace uavsim::core
