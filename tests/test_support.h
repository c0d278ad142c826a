// Test helpers: run the uavsim binary built beside the tests and capture what
// it says; temporary folders; the message of a ConfigError.
#pragma once

#include <sys/types.h>

#include <Eigen/Core>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/json_io.h"
#include "core/world_geometry.h"

namespace uavsim::testing {

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// Runs `args` (args[0] a path; no shell), stdin from /dev/null, in the
// working directory `cwd` if non-empty, capturing what it says.
CliResult RunProgram(const std::vector<std::string>& args, const std::string& cwd = "");
// Runs build/uavsim with `args` as RunProgram does.
CliResult RunCli(const std::vector<std::string>& args, const std::string& cwd = "");
// The path of `program` on $PATH, or "" if it is not there.
std::string FindOnPath(const std::string& program);

// A fresh empty temporary folder, removed at the end of the test process.
std::string TempDir(const std::string& tag);

std::string ReadFile(const std::string& path);

// How many times `what` occurs in `text` (overlaps counted).
std::size_t Count(const std::string& text, const std::string& what);

// The text between `open` and the next `close` after it ("" if absent).
std::string Between(const std::string& text, const std::string& open, const std::string& close);

// A stand-in gnuplot in `dir` that copies the script it is given to
// `script` and draws nothing; returns its path (for a spec's `gnuplot`).
std::string FakeGnuplot(const std::string& dir, const std::string& script);

// The width and height of a PNG from its IHDR chunk; 0 x 0 if not a PNG.
std::pair<int, int> PngSize(const std::string& path);
void WriteFile(const std::string& path, const std::string& content);

// Every src="..." and href="..." of an HTML page, in order.
std::vector<std::string> HtmlReferences(const std::string& html);

// What DIR/report.html references: the references that name no file in DIR,
// how many PNGs it shows, and those of them of fewer than 1000 bytes.
struct ReportReferences {
  std::vector<std::string> missing;
  std::size_t pngs = 0;
  std::vector<std::string> small_pngs;
};
ReportReferences CheckReportReferences(const std::string& dir);

// `uavsim ARGS...` started in the background as the leader of a process
// group of its own (so the group is it and the processes it forks), its
// output in `log`.out and `log`.err. The destructor kills the group if it is
// still running.
class Background {
 public:
  Background(const std::vector<std::string>& args, const std::string& log);
  ~Background();
  Background(const Background&) = delete;
  Background& operator=(const Background&) = delete;

  pid_t pid() const { return pid_; }

  // Polls every 10 ms until `ready` holds; false if the process ended first
  // or `max_s` seconds passed (a guard against hanging, not a measurement).
  bool WaitFor(const std::function<bool()>& ready, double max_s = 300.0);

  // Waits until `ready` holds, then stops the whole group (SIGSTOP) and
  // checks again, so what is seen is what a kill finds; false as WaitFor.
  bool FreezeWhen(const std::function<bool()>& ready);

  // Whether it has ended (reaps it if so).
  bool Ended();

  // Waits for it; its exit code (128 + signal if killed).
  int Wait();

 private:
  void Reaped(int status);
  pid_t pid_ = -1;
  bool ended_ = false;
  int rc_ = -1;
};

// An axis-aligned box [lo, hi] as 12 outward-wound triangles.
core::TriangleMesh BoxMesh(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                           std::uint32_t material);

// The what() of the core::ConfigError that `f` throws, or "" if none.
std::string ConfigErrorOf(const std::function<void()>& f);

// The relative paths of the regular files under `root`, sorted.
std::vector<std::string> FileList(const std::string& root);

// A run's manifest.json or metrics.json without its wall-clock fields
// (wall_s, realtime_factor, profile_s, started_utc): what two runs of the
// same scenario and seed must share.
core::Json WithoutWallClock(core::Json j);
// Catch checks that every file of run folder `a` is in `b` and the same
// byte for byte, but for metrics.json's and manifest.json's wall-clock
// fields and report.html (which shows the wall times).
void CheckSameRun(const std::string& a, const std::string& b);

}  // namespace uavsim::testing
