// `uavsim report`: redraws a run's, a sweep's or a reproduction's report.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "apps/cli/cli.h"
#include "apps/reproduce/reproduce_report.h"
#include "apps/sweep/sweep.h"
#include "core/error.h"
#include "results/run_report.h"

namespace uavsim::cli {
using core::UsageError;

int RunReportCommand(const ParsedArgs& a, int, char**) {
  if (a.positional.size() != 1)
    throw UsageError(
        "uavsim report: expected one run directory, sweep folder or reproduction (see uavsim "
        "report --help)");
  const std::string dir = a.positional[0];
  namespace fs = std::filesystem;
  std::error_code ec;
  std::vector<std::string> warnings;
  if (fs::is_regular_file(fs::path(dir) / "sweep.json", ec)) {
    warnings = sim::MergeSweep(dir).warnings;
  } else if (fs::is_regular_file(fs::path(dir) / "metrics.json", ec) &&
             fs::is_regular_file(fs::path(dir) / "manifest.json", ec)) {
    try {
      warnings = results::WriteRunReport(dir);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("uavsim report: ") + e.what());
    }
  } else if (fs::is_regular_file(fs::path(dir) / "claims.csv", ec) &&
             fs::is_regular_file(fs::path(dir) / "report.md", ec)) {
    sim::RedrawReproduceReport(dir);
  } else {
    throw UsageError("uavsim report: " + dir +
                     ": neither a run directory (no metrics.json and manifest.json), a sweep "
                     "folder (no sweep.json) nor a reproduction (no claims.csv and report.md)");
  }
  for (const std::string& w : warnings) std::cerr << "uavsim: warning: " << w << "\n";
  if (!a.Has("--quiet")) std::printf("%s/report.html written\n", dir.c_str());
  return kExitOk;
}

}  // namespace uavsim::cli
