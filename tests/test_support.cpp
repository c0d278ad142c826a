#include "test_support.h"

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/error.h"

namespace uavsim::testing {
namespace fs = std::filesystem;

namespace {
std::string Slurp(int fd) {
  std::string s;
  char buf[4096];
  ssize_t n;
  lseek(fd, 0, SEEK_SET);
  while ((n = read(fd, buf, sizeof buf)) > 0) s.append(buf, static_cast<std::size_t>(n));
  return s;
}

struct TempRoot {
  std::string path;
  TempRoot() {
    char tmpl[] = "/tmp/uavsim-test-XXXXXX";
    if (!mkdtemp(tmpl)) throw std::runtime_error("mkdtemp failed");
    path = tmpl;
  }
  ~TempRoot() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
TempRoot& Root() {
  static TempRoot root;
  return root;
}
}  // namespace

CliResult RunProgram(const std::vector<std::string>& args, const std::string& cwd) {
  FILE* out = tmpfile();
  FILE* err = tmpfile();
  const pid_t pid = fork();
  if (pid == 0) {
    const int devnull = open("/dev/null", O_RDONLY);
    dup2(devnull, STDIN_FILENO);
    dup2(fileno(out), STDOUT_FILENO);
    dup2(fileno(err), STDERR_FILENO);
    if (!cwd.empty() && chdir(cwd.c_str()) != 0) _exit(127);
    std::vector<std::string> copy = args;
    std::vector<char*> argv;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = Slurp(fileno(out));
  r.err = Slurp(fileno(err));
  fclose(out);
  fclose(err);
  return r;
}

CliResult RunCli(const std::vector<std::string>& args, const std::string& cwd) {
  std::vector<std::string> argv{UAVSIM_CLI};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunProgram(argv, cwd);
}

std::string FindOnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string d; std::getline(dirs, d, ':');) {
    const std::string candidate = (d.empty() ? std::string(".") : d) + "/" + program;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return "";
}

std::string TempDir(const std::string& tag) {
  static int counter = 0;
  const fs::path p = fs::path(Root().path) / (tag + "-" + std::to_string(counter++));
  fs::create_directories(p);
  return p.string();
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void WriteFile(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary);
  out << content;
  if (!out) throw std::runtime_error("cannot write " + path);
}

core::TriangleMesh BoxMesh(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                           std::uint32_t material) {
  core::TriangleMesh m;
  m.name = "box";
  m.material = material;
  for (int i = 0; i < 8; ++i)
    m.vertices_m.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(),
                              i & 4 ? hi.z() : lo.z());
  const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                 {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  return m;
}

std::string ConfigErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const core::ConfigError& e) {
    return e.what();
  }
  return "";
}

std::vector<std::string> HtmlReferences(const std::string& html) {
  std::vector<std::string> refs;
  const std::regex attribute("(?:src|href)=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(html.begin(), html.end(), attribute);
       it != std::sregex_iterator(); ++it)
    refs.push_back((*it)[1].str());
  return refs;
}

ReportReferences CheckReportReferences(const std::string& dir) {
  ReportReferences out;
  for (const std::string& f : HtmlReferences(ReadFile(dir + "/report.html"))) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(dir + "/" + f, ec)) {
      out.missing.push_back(f);
      continue;
    }
    if (f.size() > 4 && f.compare(f.size() - 4, 4, ".png") == 0) {
      ++out.pngs;
      if (std::filesystem::file_size(dir + "/" + f, ec) < 1000) out.small_pngs.push_back(f);
    }
  }
  return out;
}

Background::Background(const std::vector<std::string>& args, const std::string& log) {
  std::vector<std::string> copy = args;
  copy.insert(copy.begin(), UAVSIM_CLI);
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string out = log + ".out", err = log + ".err";
  pid_ = fork();
  if (pid_ == 0) {
    setpgid(0, 0);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    const int devnull = open("/dev/null", O_RDONLY);
    dup2(devnull, STDIN_FILENO);
    const int o = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(o, STDOUT_FILENO);
    dup2(e, STDERR_FILENO);
    execv(argv[0], argv.data());
    _exit(127);
  }
  setpgid(pid_, pid_);  // whichever of parent and child gets here first
}

Background::~Background() {
  if (!ended_) {
    kill(-pid_, SIGKILL);
    Wait();
  }
}

bool Background::WaitFor(const std::function<bool()>& ready, double max_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(max_s);
  while (!Ended()) {
    if (ready()) return true;
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

bool Background::FreezeWhen(const std::function<bool()>& ready) {
  while (WaitFor(ready)) {
    kill(-pid_, SIGSTOP);
    if (ready()) return true;
    kill(-pid_, SIGCONT);
  }
  return false;
}

bool Background::Ended() {
  int status = 0;
  if (!ended_ && waitpid(pid_, &status, WNOHANG) == pid_) Reaped(status);
  return ended_;
}

int Background::Wait() {
  int status = 0;
  if (!ended_ && waitpid(pid_, &status, 0) == pid_) Reaped(status);
  return rc_;
}

void Background::Reaped(int status) {
  ended_ = true;
  rc_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::size_t Count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::string Between(const std::string& text, const std::string& open, const std::string& close) {
  const auto a = text.find(open);
  if (a == std::string::npos) return "";
  const auto b = text.find(close, a + open.size());
  return b == std::string::npos ? "" : text.substr(a + open.size(), b - a - open.size());
}

std::string FakeGnuplot(const std::string& dir, const std::string& script) {
  const std::string fake = dir + "/fake-gnuplot";
  WriteFile(fake, "#!/bin/sh\ncp \"$1\" '" + script + "'\n");
  std::filesystem::permissions(fake, std::filesystem::perms::owner_all);
  return fake;
}

std::pair<int, int> PngSize(const std::string& path) {
  if (!std::filesystem::exists(path)) return {0, 0};
  const std::string png = ReadFile(path);
  if (png.size() < 24 || png.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0) return {0, 0};
  const auto be32 = [&](std::size_t at) {
    int v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = v * 256 + static_cast<unsigned char>(png[at + i]);
    return v;
  };
  return {be32(16), be32(20)};
}

std::vector<std::string> FileList(const std::string& root) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(root))
    if (e.is_regular_file()) files.push_back(std::filesystem::relative(e.path(), root).string());
  std::sort(files.begin(), files.end());
  return files;
}

core::Json WithoutWallClock(core::Json j) {
  for (const char* k : {"wall_s", "realtime_factor", "profile_s", "started_utc"}) j.erase(k);
  return j;
}

void CheckSameRun(const std::string& a, const std::string& b) {
  const auto files = FileList(a);
  REQUIRE(files.size() > 8);
  CHECK(FileList(b) == files);
  for (const std::string& f : files) {
    INFO(f);
    if (!fs::exists(b + "/" + f) || f == "report.html") continue;
    if (f == "metrics.json" || f == "manifest.json")
      CHECK(WithoutWallClock(core::Json::parse(ReadFile(a + "/" + f))) ==
            WithoutWallClock(core::Json::parse(ReadFile(b + "/" + f))));
    else
      CHECK(ReadFile(a + "/" + f) == ReadFile(b + "/" + f));
  }
}

}  // namespace uavsim::testing
