#include "core/file_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/error.h"
#include "core/interrupt.h"

namespace uavsim::core {
namespace {

// What the holder wrote: "PID COMMAND LINE" ("" if it has not yet).
std::string Holder(int fd) {
  std::string text(4096, '\0');
  const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
  text.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\0')) text.pop_back();
  return text;
}

}  // namespace

std::string OwnCommandLine() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!all.empty() && all.back() == '\0') all.pop_back();
  for (char& c : all)
    if (c == '\0') c = ' ';
  return all;
}

FileLock::FileLock(const std::string& path, const std::string& what, bool wait) : path_(path) {
  // A holder removes the file as it lets go: the lock taken must be on the
  // file that still has the name, else take it again on the new one.
  while (!TakeOnce(what, wait)) {
  }
  // Ours: say who holds it.
  const std::string me = std::to_string(::getpid()) + " " + OwnCommandLine() + "\n";
  if (::ftruncate(fd_, 0) == 0) {
    [[maybe_unused]] const ssize_t n = ::pwrite(fd_, me.data(), me.size(), 0);
  }
}

bool FileLock::TakeOnce(const std::string& what, bool wait) {
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error(path_ + ": cannot open lock file: " + std::strerror(errno));
  while (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EINTR) continue;
    if (errno != EWOULDBLOCK) {
      const std::string why = std::strerror(errno);
      ::close(fd_);
      throw std::runtime_error(path_ + ": cannot lock: " + why);
    }
    if (!wait) {
      std::string holder = Holder(fd_);
      ::close(fd_);
      const auto space = holder.find(' ');
      const std::string pid = holder.substr(0, space);
      const std::string command = space == std::string::npos ? "" : holder.substr(space + 1);
      throw UsageError(what + ": in use by process " + (pid.empty() ? "?" : pid) +
                       (command.empty() ? "" : " (" + command + ")") + " (lock " + path_ +
                       "); pass --wait to wait for it");
    }
    if (InterruptRequested()) {
      ::close(fd_);
      throw Interrupted();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  struct stat held {
  }, named{};
  if (::fstat(fd_, &held) == 0 && ::stat(path_.c_str(), &named) == 0 &&
      held.st_dev == named.st_dev && held.st_ino == named.st_ino)
    return true;
  ::close(fd_);  // the holder before us removed it: the name is a new file's
  return false;
}

FileLock::~FileLock() {
  // Unlinked while still held (a waiter on this file then sees it gone and
  // takes the new one), then released. A killed holder leaves the file,
  // unlocked: the next holder removes it.
  ::unlink(path_.c_str());
  ::close(fd_);
}

}  // namespace uavsim::core
