#include "results/plot.h"

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
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "results/csv.h"

extern char** environ;

namespace uavsim::results {
namespace {

namespace fs = std::filesystem;

// A gnuplot string expression for `s`. Single-quoted gnuplot strings are
// taken literally (no backquote commands, no macros, no backslash escapes);
// their one escape, '', is ambiguous next to an opening quote, so a quote
// character is spliced in as the double-quoted "'" instead. A newline would
// end the command: control characters become spaces.
std::string Quote(const std::string& s) {
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

bool HasControlChars(const std::string& s) {
  for (char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return true;
  return false;
}

bool ParseNumber(const std::string& s, double* x) {
  const char* end = s.data() + s.size();
  const auto r = std::from_chars(s.data(), end, *x);
  return r.ec == std::errc() && r.ptr == end && std::isfinite(*x);
}

std::string Shortest(double x) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

struct Series {
  std::string name;
  std::string points;  // "x y\n" lines ("x y half-width\n" with error bars)
};

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

std::string PlotCsv(const std::string& csv_path, const PlotSpec& spec) {
  const std::string where = "plot " + csv_path + ": ";
  if (spec.gnuplot.empty()) return where + "no gnuplot program given";
  if (spec.width_px < 64 || spec.width_px > 8192 || spec.height_px < 64 || spec.height_px > 8192)
    return where + "image size must be within 64..8192 pixels";
  const std::string png =
      spec.png_path.empty() ? fs::path(csv_path).replace_extension(".png").string() : spec.png_path;
  // A path is written into the script; a control character there would
  // become another file's name, so refuse it rather than rewrite it.
  if (HasControlChars(png)) return where + "the PNG path contains control characters";

  std::ifstream in(csv_path, std::ios::binary);
  if (!in) return where + "cannot read the file";
  std::string line;
  if (!std::getline(in, line)) return where + "the file is empty";
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = SplitCsvLine(line);
  const auto column = [&](const std::string& name) -> long {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return static_cast<long>(i);
    return -1;
  };
  const long xc = column(spec.x_column), yc = column(spec.y_column);
  const long gc = spec.group_column.empty() ? -2 : column(spec.group_column);
  if (xc < 0) return where + "no column \"" + spec.x_column + "\"";
  if (yc < 0) return where + "no column \"" + spec.y_column + "\"";
  if (gc == -1) return where + "no column \"" + spec.group_column + "\"";
  const long ebc = spec.y_error_column.empty() ? -2 : column(spec.y_error_column);
  if (ebc == -1) return where + "no column \"" + spec.y_error_column + "\"";

  std::vector<Series> series;
  std::size_t row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::vector<std::string> cells = SplitCsvLine(line);
    if (cells.size() != header.size())
      return where + "line " + std::to_string(row) + " has " + std::to_string(cells.size()) +
             " cells, the header " + std::to_string(header.size());
    const std::string at = where + "line " + std::to_string(row) + ": ";
    double x = 0.0, y = 0.0, half_width = 0.0;
    const bool y_missing = spec.skip_empty_y && cells[yc].empty();
    if (!ParseNumber(cells[xc], &x) || (!y_missing && !ParseNumber(cells[yc], &y)))
      return at + "expected finite numbers in \"" + spec.x_column + "\" and \"" + spec.y_column +
             "\"";
    if (spec.log_x && x <= 0.0) return at + "x must be > 0 on a logarithmic axis";
    if (spec.log_y && !y_missing && y <= 0.0) return at + "y must be > 0 on a logarithmic axis";
    if (ebc >= 0 && !cells[ebc].empty() &&
        (!ParseNumber(cells[ebc], &half_width) || half_width < 0))
      return at + "expected an empty cell or a finite number >= 0 in \"" + spec.y_error_column +
             "\"";
    if (y_missing) continue;
    const std::string group = gc >= 0 ? cells[gc] : spec.y_column;
    Series* s = nullptr;
    for (auto& candidate : series)
      if (candidate.name == group) s = &candidate;
    if (!s) {
      series.push_back({group, ""});
      s = &series.back();
    }
    s->points += Shortest(x) + " " + Shortest(y);
    if (ebc >= 0) s->points += " " + Shortest(half_width);
    s->points += "\n";
  }
  if (series.empty()) return where + "no data rows";

  const fs::path final_png(png);
  const std::string tmp_png = (final_png.parent_path() / ("." + final_png.filename().string() +
                                                          ".tmp-" + std::to_string(getpid())))
                                  .string();
  TempFile tmp_png_guard{tmp_png};

  // Texts go through variables: `set title`, `set output` and `title` all
  // take a string expression there.
  std::ostringstream gp;
  gp << "uavsim_output = " << Quote(tmp_png) << "\n"
     << "uavsim_title = " << Quote(spec.title) << "\n"
     << "uavsim_xlabel = " << Quote(spec.x_label) << "\n"
     << "uavsim_ylabel = " << Quote(spec.y_label) << "\n";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << "uavsim_line" << i << " = " << Quote(series[i].name) << "\n";
  gp << "set encoding utf8\n"
     << "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
     << "  set terminal pngcairo size " << spec.width_px << "," << spec.height_px << " noenhanced\n"
     << "} else {\n"
     << "  set terminal png size " << spec.width_px << "," << spec.height_px << " noenhanced\n"
     << "}\n"
     << "set output uavsim_output\n"
     << "set datafile separator whitespace\n"
     << "set title uavsim_title\n"
     << "set xlabel uavsim_xlabel\n"
     << "set ylabel uavsim_ylabel\n"
     << "set grid\n"
     << (spec.key_below ? "set key below\n" : "set key top left\n");
  if (spec.log_x) gp << "set logscale x\n";
  if (spec.log_y) gp << "set logscale y\n";
  if (spec.y_min_zero && !spec.log_y) gp << "set yrange [0:*]\n";
  // Error bars at the ends of the x range would be drawn on the border.
  if (ebc >= 0) gp << "set offsets graph 0.03, graph 0.03, 0, 0\n";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << "$g" << i << " << EOD\n" << series[i].points << "EOD\n";
  gp << "plot ";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << (i ? ", \\\n     " : "") << "$g" << i
       << (ebc >= 0 ? " using 1:2:3 with yerrorlines" : " using 1:2 with linespoints")
       << " title uavsim_line" << i;
  gp << "\nunset output\n";

  std::string script_path = (fs::temp_directory_path() / "uavsim-plot-XXXXXX.gp").string();
  const int fd = mkstemps(script_path.data(), 3);
  if (fd < 0) return where + "cannot create a temporary script: " + std::strerror(errno);
  TempFile script_guard{script_path};
  const std::string text = gp.str();
  const ssize_t written = write(fd, text.data(), text.size());
  close(fd);
  if (written != static_cast<ssize_t>(text.size()))
    return where + "cannot write the temporary script";

  const std::string failure = Run({spec.gnuplot, script_path});
  if (!failure.empty()) return where + failure;
  std::error_code ec;
  const auto png_bytes = fs::file_size(tmp_png, ec);
  if (ec || png_bytes == 0) return where + "gnuplot wrote no image";
  fs::rename(tmp_png, png, ec);
  if (ec) return where + "cannot rename the image to " + png + ": " + ec.message();
  tmp_png_guard.path.clear();
  return "";
}

}  // namespace uavsim::results
