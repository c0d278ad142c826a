#include "results/gnuplot.h"

#include <fcntl.h>
#include <spawn.h>
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

extern char** environ;

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;

bool HasControlChars(const std::string& s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return true;
  return false;
}

// Runs argv (no shell) with stdin from /dev/null and stdout+stderr captured.
// Returns "" on exit status 0, else the reason.
std::string Run(const std::vector<std::string>& args) {
  int fds[2];
  if (pipe(fds) != 0) return std::string("cannot create a pipe: ") + std::strerror(errno);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  posix_spawn_file_actions_addclose(&actions, fds[0]);
  posix_spawn_file_actions_addclose(&actions, fds[1]);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int err = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (err != 0) {
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
