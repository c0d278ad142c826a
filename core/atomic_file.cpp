#include "core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace uavsim::core {
namespace fs = std::filesystem;

namespace {
std::runtime_error IoError(const std::string& what, const std::string& path) {
  return std::runtime_error(path + ": " + what + ": " + std::strerror(errno));
}

// A temporary name in `path`'s folder (the rename cannot cross file
// systems), hidden, unique to this process.
std::string TemporaryBeside(const std::string& path) {
  const fs::path p(path);
  return (p.parent_path() / ("." + p.filename().string() + ".tmp-" + std::to_string(::getpid())))
      .string();
}
}  // namespace

void WriteFileAtomic(const std::string& path, const std::string& content) {
  const std::string tmp = TemporaryBeside(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError("cannot create", tmp);
  const char* data = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const auto err = IoError("cannot write", tmp);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw err;
    }
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) {
    const auto err = IoError("cannot write", tmp);
    ::unlink(tmp.c_str());
    throw err;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const auto err = IoError("cannot rename into place", path);
    ::unlink(tmp.c_str());
    throw err;
  }
}

void WriteViaTemporary(const std::string& path,
                       const std::function<void(const std::string&)>& write) {
  // "<path>.tmp-PID": torch::save names the folder inside its zip archive
  // after the file name's stem, which is then <path>'s own file name, the
  // same for every run (so the same weights give the same bytes).
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  try {
    write(tmp);
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const auto err = IoError("cannot rename into place", path);
    ::unlink(tmp.c_str());
    throw err;
  }
}

std::string ReadFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace uavsim::core
