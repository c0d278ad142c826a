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
namespace {

using core::UsageError;

const char* kHelp =
    "usage: uavsim report DIR [--quiet]\n"
    "\n"
    "Redraws the report of a run directory (report.html, report/, rate_snr.png) or of a\n"
    "finished sweep folder (summary.csv, aggregate.csv, plots/, report.html) from the\n"
    "files already there, without simulating anything: after a change of style, or for a\n"
    "directory made by an older uavsim (figures whose input file it lacks say so).\n"
    "For a folder of uavsim reproduce (claims.csv, the artefact CSVs, report.md: what\n"
    "docs/paper keeps) it redraws the verdicts from claims.csv with this binary's rules,\n"
    "training nothing: claims.csv and the verdict sections of report.md/report.html.\n"
    "Open DIR/report.html in a browser; it needs no network access.\n"
    "\n"
    "  --quiet   print nothing on success (warnings about figures not drawn still go to\n"
    "            stderr)\n"
    "exit codes: 0 written, 2 DIR is neither a run directory, a finished sweep nor a\n"
    "reproduction, or one of its files is malformed\n";

int Report(const ParsedArgs& a, int, char**) {
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

std::string Help() { return kHelp; }

}  // namespace

Command ReportCommand() {
  return {"report", "report DIR", "redraw a run's or a sweep's report.html from its files",
          {},       Help,         Report};
}

}  // namespace uavsim::cli
