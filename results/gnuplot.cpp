#include "results/gnuplot.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "core/child_process.h"

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;

bool HasControlChars(const std::string& s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return true;
  return false;
}

// Starts argv (no shell, PATH searched) in a child that dies with this
// process (core/child_process.h: a plot never lands in a killed command's
// output), stdin from /dev/null, stdout and stderr into `out_fd`. Returns
// the child's pid, or -1 with `err` set to why it could not start.
pid_t Spawn(const std::vector<std::string>& args, int out_fd, int& err) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  int status_pipe[2];  // the exec's errno, if it fails; closed by a good exec
  if (pipe2(status_pipe, O_CLOEXEC) != 0) {
    err = errno;
    return -1;
  }
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {  // only async-signal-safe calls until exec
    core::DieWithParent(parent);
    const int null_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (null_fd < 0 || dup2(null_fd, 0) < 0 || dup2(out_fd, 1) < 0 || dup2(out_fd, 2) < 0) {
      const int e = errno;
      (void)!write(status_pipe[1], &e, sizeof e);
      _exit(127);
    }
    execvp(argv[0], argv.data());
    const int e = errno;
    (void)!write(status_pipe[1], &e, sizeof e);
    _exit(127);
  }
  const int fork_errno = errno;
  close(status_pipe[1]);
  if (pid < 0) {
    close(status_pipe[0]);
    err = fork_errno;
    return -1;
  }
  int child_errno = 0;
  ssize_t n;
  while ((n = read(status_pipe[0], &child_errno, sizeof child_errno)) < 0 && errno == EINTR) {
  }
  close(status_pipe[0]);
  if (n == static_cast<ssize_t>(sizeof child_errno)) {
    while (waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
    }
    err = child_errno;
    return -1;
  }
  return pid;
}

// Runs argv (no shell) with stdin from /dev/null and stdout+stderr captured.
// Returns "" on exit status 0, else the reason.
std::string Run(const std::vector<std::string>& args) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0)
    return std::string("cannot create a pipe: ") + std::strerror(errno);
  int err = 0;
  const pid_t pid = Spawn(args, fds[1], err);
  close(fds[1]);
  if (pid < 0) {
    close(fds[0]);
    if (err == ENOENT)
      return "gnuplot not found (\"" + args[0] + "\"): install gnuplot to get PNG plots";
    return "cannot start \"" + args[0] + "\": " + std::strerror(err);
  }
  std::string output;
  char buf[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n > 0) {
      output.append(buf, static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;
    }
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  std::string first;
  std::istringstream lines(output);
  for (std::string line; std::getline(lines, line);)
    if (line.find_first_not_of(" \t^") != std::string::npos) {
      first = line;
      break;
    }
  for (char& c : first)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  return "gnuplot failed" + (first.empty() ? std::string() : ": " + first);
}

// Deletes a file at the end of the scope.
struct TempFile {
  std::string path;
  ~TempFile() {
    if (!path.empty()) std::remove(path.c_str());
  }
};

}  // namespace

// Single-quoted gnuplot strings are taken literally (no backquote commands,
// no macros, no backslash escapes); their one escape, '', is ambiguous next
// to an opening quote, so a quote character is spliced in as the
// double-quoted "'" instead.
std::string GnuplotString(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\'')
      out += "'.\"'\".'";
    else if (u < 0x20 || u == 0x7f)
      out += ' ';
    else
      out += c;
  }
  return out + "'";
}

std::string ShortestNumber(double x) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

bool ParseFiniteNumber(const std::string& s, double* x) {
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, *x);
  return r.ec == std::errc() && r.ptr == end && std::isfinite(*x);
}

std::string RunGnuplot(const std::string& script, const GnuplotImage& image) {
  if (image.gnuplot.empty()) return "no gnuplot program given";
  if (image.width_px < 64 || image.width_px > 8192 || image.height_px < 64 ||
      image.height_px > 8192)
    return "image size must be within 64..8192 pixels";
  // A path is written into the script; a control character there would
  // become another file's name, so refuse it rather than rewrite it.
  if (HasControlChars(image.png_path)) return "the PNG path contains control characters";
  const fs::path final_png(image.png_path);
  const std::string tmp_png = (final_png.parent_path() / ("." + final_png.filename().string() +
                                                          ".tmp-" + std::to_string(getpid())))
                                  .string();
  TempFile tmp_png_guard{tmp_png};

  std::ostringstream gp;
  const std::string size = std::to_string(image.width_px) + "," + std::to_string(image.height_px);
  gp << "uavsim_output = " << GnuplotString(tmp_png) << "\n"
     << "uavsim_font = " << GnuplotString(image.font) << "\n"
     << "set encoding utf8\n"
     << "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
     << "  set terminal pngcairo size " << size << " noenhanced"
     << (image.font.empty() ? "" : " font uavsim_font") << "\n"
     << "} else {\n"
     << "  set terminal png size " << size << " noenhanced\n"
     << "}\n"
     << "set output uavsim_output\n"
     << script << "\nunset output\n";

  std::string script_path = (fs::temp_directory_path() / "uavsim-plot-XXXXXX.gp").string();
  const int fd = mkstemps(script_path.data(), 3);
  if (fd < 0) return std::string("cannot create a temporary script: ") + std::strerror(errno);
  TempFile script_guard{script_path};
  const std::string text = gp.str();
  const ssize_t written = write(fd, text.data(), text.size());
  close(fd);
  if (written != static_cast<ssize_t>(text.size())) return "cannot write the temporary script";

  const std::string failure = Run({image.gnuplot, script_path});
  if (!failure.empty()) return failure;
  std::error_code ec;
  const auto png_bytes = fs::file_size(tmp_png, ec);
  if (ec || png_bytes == 0) return "gnuplot wrote no image";
  fs::rename(tmp_png, image.png_path, ec);
  if (ec) return "cannot rename the image to " + image.png_path + ": " + ec.message();
  tmp_png_guard.path.clear();
  return "";
}

}  // namespace uavsim::results
